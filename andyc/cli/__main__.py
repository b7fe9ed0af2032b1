"""`python -m andyc.cli`: the command line, as the `andyc` command."""

from andyc.cli import main

if __name__ == "__main__":
    main()
