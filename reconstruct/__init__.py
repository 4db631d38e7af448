"""Image stage: turntable photographs of a fingertip replica -> axial sections -> closed surface."""
from common.errors import InputError

__all__ = ["InputError"]
