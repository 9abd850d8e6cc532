"""``python -m mbseig``: the command line."""

from .cli import console

console()
