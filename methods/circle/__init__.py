"""Circle family: importing this package registers its methods."""
from methods.circle import (algebraic, gauss_newton, levenberg_marquardt, minimum_zone,  # noqa: F401
                            nelder_mead, powell_hybrid)
