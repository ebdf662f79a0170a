"""``python -m bipedal_cli``: the same as the ``bipedal`` command."""

from .cli import main

if __name__ == "__main__":
    main()
