"""`python -m lumos ...` runs the `lumos` command."""

from .cli import run

if __name__ == "__main__":
    run()
