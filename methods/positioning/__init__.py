"""Positioning accuracy of NC axes (ISO 230-2) and the polynomial model with its uncertainty
(Kureková et al., the positioning paper). Importing this package registers the family."""
from methods.positioning import iso230_2, model  # noqa: F401
from methods.positioning.data import PositioningData, from_frame

__all__ = ["PositioningData", "from_frame"]
