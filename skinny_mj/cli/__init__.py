"""The ``skinny`` command: the parser, the handlers of its sub-commands,
the checks of its flags, the help texts, the bench and the viewer."""
