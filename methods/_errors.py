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
