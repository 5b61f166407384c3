"""The native half of the package: the Rust `situate` program (crate `situate_py`)."""

def main(argv: list[str]) -> int:
    """Runs the `situate` program with `argv` (first item: the program name); returns its exit code.

    The GIL is released while it runs.
    """

def version() -> str:
    """The version of the built-in `situate` program."""
