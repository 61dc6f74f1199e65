"""``python -m dvrk_ident ARGS``: the ``dvrk-ident`` command line."""

from ._cli import main

main()
