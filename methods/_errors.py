"""The one exception type for bad input, shared by every method, reader and CLI."""


class InvalidInputError(ValueError):
    """Input a method cannot fit: the message says what is wrong and what to do."""


class UnknownMethodError(InvalidInputError, LookupError):
    """A method id that is not registered (the message suggests close ids)."""


class ResultContractError(InvalidInputError):
    """A method returned a result that breaks its family's contract (:func:`methods.check_result`: e.g. a
    converged circle of radius 0): it is refused, never shown as a fit. ``problem`` is the gate's one-line reason."""

    def __init__(self, method_id: str, problem: str):
        self.method_id, self.problem = method_id, problem
        super().__init__(f"{method_id} returned a result that breaks its family's contract: {problem}; "
                         f"the result is refused (check the parameters, or report it to the method's author)")


def _type_name(exc: BaseException) -> str:
    name = getattr(type(exc), "__name__", None)
    return name if type(name) is str else "an exception"


def _printed(func, value):
    """``func(value)`` as a str, or None when it raises or gives no str (a Ctrl-C while printing is not swallowed)."""
    try:
        text = func(value)
    except KeyboardInterrupt:
        raise
    except BaseException:   # an exception's own __str__/__repr__ is outside code: whatever it raises
        return None
    return text if isinstance(text, str) else None


def exception_text(exc: BaseException) -> str:
    """``Type: message`` of ``exc`` (``Type`` alone for an empty message), never raising: an exception whose
    ``str()`` raises is described by its own type, ``BadStr (its message cannot be printed: RuntimeError: ...)``,
    never by the exception its ``__str__`` raised (which the caller would then blame). For messages of rows and
    command lines about an exception raised by code outside fitbench (a plugin method)."""
    name = _type_name(exc)
    try:
        text = str(exc)
        if not isinstance(text, str):
            raise TypeError(f"__str__ returned {_type_name(text)}")
    except KeyboardInterrupt:
        raise
    except BaseException as inner:   # outside code: anything may come out of it
        detail = _printed(str, inner)
        inner_text = f"{_type_name(inner)}: {detail}" if detail else _type_name(inner)
        return f"{name} (its message cannot be printed: {inner_text})"
    return f"{name}: {text}" if text else name


def exception_call(exc: BaseException) -> str:
    """``Type(arg, ...)`` of ``exc`` from the ``repr`` of its arguments, never raising (an argument whose repr
    raises is shown as ``<Type object>``): how an exception that is not an :class:`Exception` (``SystemExit(0)``, a
    plugin's ``BaseException`` subclass) is named, its arguments being all it says."""
    args = getattr(exc, "args", ())
    if not isinstance(args, tuple):
        args = ()
    shown = [_printed(repr, a) or f"<{_type_name(a)} object>" for a in args]
    return f"{_type_name(exc)}({', '.join(shown)})"
