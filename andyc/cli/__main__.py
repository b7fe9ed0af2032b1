"""`python -m andyc.cli`: the command line, as the `andyc` command."""

from andyc.cli import run

if __name__ == "__main__":
    run()
