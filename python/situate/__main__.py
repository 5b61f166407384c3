"""``python -m situate``: the ``situate`` program, as the console script runs it."""

from situate._cli import main

if __name__ == "__main__":
    main()
