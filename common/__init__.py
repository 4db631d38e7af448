"""What every stage shares and no stage's science depends on another for: the one-line input
error, atomic output, and the table writer."""
from common.errors import InputError

__all__ = ["InputError"]
