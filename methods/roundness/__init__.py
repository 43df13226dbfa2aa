"""Roundness as ISO 12181 defines it: the ISO 16610-21 closed-profile Gaussian filter (cut-off in UPR),
RONt/RONp/RONv/RONq about the four reference circles (LSCI, MZCI, MICI, MCCI) and the harmonic spectrum.
Importing this package registers ``roundness.iso12181``."""
from methods.roundness import iso12181  # noqa: F401  (registers the method)
from methods.roundness.evaluation import REFERENCES, evaluate, filtered_profile, ron_parameters
from methods.roundness.filter import (ALPHA, STANDARD_CUTOFFS_UPR, UndersampledWarning, dominant_lobes, fft_filter,
                                      gaussian_filter, harmonic_spectrum, parse_cutoff, transmission)
from methods.roundness.results import RoundnessFit

__all__ = ["evaluate", "filtered_profile", "ron_parameters", "REFERENCES", "ALPHA", "STANDARD_CUTOFFS_UPR",
           "UndersampledWarning", "transmission", "fft_filter", "gaussian_filter", "harmonic_spectrum",
           "dominant_lobes", "parse_cutoff", "RoundnessFit"]
