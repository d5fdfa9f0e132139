"""The ``coherent`` console script: the Rust command line, run from the extension module."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Sequence

from ._coherent import cli_main


def main(argv: Sequence[str] | None = None) -> None:
    """Runs ``coherent`` with ``argv`` (default: the process's arguments) and exits with
    its status."""
    # Python turns SIGINT into KeyboardInterrupt, which would only be seen once the
    # Rust code returns; the default action ends the process at once, like the binary.
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    args = sys.argv[1:] if argv is None else list(argv)
    # Rust writes to the file descriptor directly: flush what Python buffered first.
    sys.stdout.flush()
    sys.stderr.flush()
    sys.exit(cli_main(["coherent", *args]))


if __name__ == "__main__":
    main()
