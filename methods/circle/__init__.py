"""Circle family: importing this package registers its methods."""
from methods.circle import algebraic, gauss_newton, levenberg_marquardt, nelder_mead, powell_hybrid  # noqa: F401
