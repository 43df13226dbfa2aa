"""The result classes moved to the public :mod:`methods.results`; this name stays for the family modules
that import it (``from methods._result import circle_result``)."""
from methods.results import *  # noqa: F401,F403
from methods.results import _center_errors, _compiled_residuals, _jsonable, _num  # noqa: F401
