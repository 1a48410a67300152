"""``python -m skinny_mj.cli``: the ``skinny`` command."""

import sys

from skinny_mj.cli.parser import main

sys.exit(main())
