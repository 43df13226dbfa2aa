"""Multilateration for volumetric errors (Holub et al., Machines 2022, 10, 833): stations and dead paths,
actual tool positions, volumetric errors, and the 21 geometric errors of a 3-axis machine.
Importing this package registers the family."""
from methods.multilateration import schemes  # noqa: F401
from methods.multilateration.data import MultilaterationData, from_frame
from methods.multilateration.kinematics import ErrorModel, identify, volumetric_errors

__all__ = ["MultilaterationData", "from_frame", "ErrorModel", "identify", "volumetric_errors"]
