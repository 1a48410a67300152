#!/usr/bin/env bash
# Re-render the diagrams after editing a NAME.mmd: writes NAME.svg beside it (committed, so
# the docs site loads nothing from the network). Needs @mermaid-js/mermaid-cli 11 (`mmdc`;
# `npm install @mermaid-js/mermaid-cli`, with PUPPETEER_EXECUTABLE_PATH=/usr/bin/chromium
# to use Debian's chromium). The root <svg> gets its natural size as width/height, so the
# page shows it at that size (mermaid writes width="100%", which stretches it).
set -euo pipefail
cd "$(dirname "$0")"
for src in *.mmd; do
    out="${src%.mmd}.svg"
    mmdc -c mermaid.json -b white -i "$src" -o "$out" ${PUPPETEER_CONFIG:+-p "$PUPPETEER_CONFIG"}
    python3 - "$out" <<'PY'
import re, sys
path = sys.argv[1]
svg = open(path).read()
w, h = re.search(r'<svg[^>]*viewBox="[-\d.]+ [-\d.]+ ([\d.]+) ([\d.]+)"', svg).groups()
head, rest = svg.split(">", 1)
head = re.sub(r' width="100%"', f' width="{float(w):.0f}" height="{float(h):.0f}"', head)
head = re.sub(r' style="max-width: [\d.]+px;[^"]*"', "", head)
open(path, "w").write(head + ">" + rest)
PY
done
