"""`python -m lumos ...` runs the `lumos` command."""

from .cli import main

if __name__ == "__main__":
    raise SystemExit(main())
