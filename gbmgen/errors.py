"""Exceptions raised by this package."""


class InputError(ValueError):
    """Bad user input: the message names the file or field and what was expected."""
