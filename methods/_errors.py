"""The one exception type for bad input, shared by every method, reader and CLI."""


class InvalidInputError(ValueError):
    """Input a method cannot fit: the message says what is wrong and what to do."""


class UnknownMethodError(InvalidInputError, LookupError):
    """A method id that is not registered (the message suggests close ids)."""
