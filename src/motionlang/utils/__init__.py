"""Small shared helpers: atomic file writes and progress bars."""
from motionlang.utils.atomic import atomic_path, atomic_write
from motionlang.utils.progress import progress

__all__ = ["atomic_write", "atomic_path", "progress"]
