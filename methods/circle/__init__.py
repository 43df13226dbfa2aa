"""Circle family: importing this package registers its methods."""
from methods.circle import (algebraic, chebyshev, extreme_circles, gauss_newton,  # noqa: F401
                            levenberg_marquardt, minimum_zone, nelder_mead, powell_hybrid)
