"""``python -m symvib.cli``: the ``symvib`` command."""
from symvib.cli.command import leave, main

if __name__ == "__main__":  # pragma: no cover
    leave(main())
