"""The `glaswave` command of a pip-installed package: the C++ program installed beside the module
(glaswave/bin/glaswave), run in this process's place with the same arguments, so that its exit
status, signals and mpirun's environment are the program's own."""
import os
import sys


def main():
    program = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin", "glaswave")
    if not os.access(program, os.X_OK):
        sys.exit(f"glaswave: error: the glaswave program is missing from this installation "
                 f"({program}); reinstall the package")
    os.execv(program, [program, *sys.argv[1:]])
