"""Exceptions raised by :mod:`sim`."""


class InputError(ValueError):
    """Bad user input: names the file or field and what was expected."""


class InstabilityError(RuntimeError):
    """The integration became unstable.

    Attributes
    ----------
    step : int
        Last good step.
    cause : str
        ``"nan"``, ``"energy"`` or ``"overlap"``.
    """

    def __init__(self, message, *, step=-1, cause="", index=-1):
        super().__init__(message)
        self.step = step
        self.cause = cause
        self.index = index
