"""Image stage: turntable photographs of a fingertip replica -> axial sections -> closed surface."""
from reconstruct.errors import InputError

__all__ = ["InputError"]
