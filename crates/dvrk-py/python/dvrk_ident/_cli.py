"""The ``dvrk-ident`` command installed with the wheel, and ``python -m dvrk_ident``:
the command line of the Rust binary, compiled into the extension module, run in this
process."""

import signal
import sys


def main(argv=None):
    """Runs ``dvrk-ident`` with ``argv`` (default: the process's arguments) and exits
    with its status."""
    from .dvrk_ident import _cli_main

    args = sys.argv[1:] if argv is None else list(argv)
    # As the binary: Ctrl-C ends the process (Python's handler would only raise
    # KeyboardInterrupt after the command returned).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.stdout.flush()
    sys.exit(_cli_main(["dvrk-ident", *args]))
