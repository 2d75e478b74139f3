"""The `ribbar` command line, as installed by the Python package.

Runs the same command line as the Rust binary, in this process, after
pointing it at the gmsh that the package's `gmsh` dependency installed and
at this program for the child processes that studies start.
"""

import signal
import sys

from ribbar._environment import prepare_environment


def main() -> int:
    prepare_environment()
    # The command line runs in native code that never returns to the
    # interpreter's signal handler: Ctrl-C must end the process as it ends
    # the Rust binary (a killed solve resumes from its last checkpoint).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    from ribbar import _native

    return _native.main(["ribbar", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
