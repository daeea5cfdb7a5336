"""Disk cache of prefiltered cube maps, keyed by environment content hash, exponent and sizes.

The cache directory is whatever the caller passes, else ``$CACAD_CACHE_DIR``, else
``~/.cache/cacad``; prefiltered maps go under ``<dir>/prefilter/``. Nothing is kept at module level:
each :class:`PrefilterCache` is an explicit object. Files are ``.npy`` float16 written atomically
(temporary name, then rename), so concurrent writers never leave a half-written entry; an entry that
fails to load is treated as a miss and rewritten.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

CACHE_VERSION = 1


def default_cache_dir() -> Path:
    """``$CACAD_CACHE_DIR`` or ``~/.cache/cacad``."""
    env = os.environ.get("CACAD_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "cacad"


class PrefilterCache:
    """Prefiltered maps on disk under ``<root>/prefilter``."""

    def __init__(self, root: str | Path | None = None) -> None:
        self.root = (Path(root) if root is not None else default_cache_dir()) / "prefilter"

    @staticmethod
    def key(env_hash: str, exponent: float, out_size: int, src_size: int, samples: int, engine: str) -> str:
        """File stem for one prefiltered map."""
        return f"{env_hash[:40]}-n{exponent:.6g}-o{out_size}-s{src_size}-N{samples}-{engine}-v{CACHE_VERSION}"

    def get(self, key: str) -> np.ndarray | None:
        """The cached cube (6, S, S, 3) float32, or None on a miss or an unreadable entry."""
        path = self.root / f"{key}.npy"
        try:
            return np.load(path).astype(np.float32)
        except (OSError, ValueError):
            return None

    def put(self, key: str, cube: np.ndarray) -> None:
        """Store *cube* as float16 (atomic rename)."""
        self.root.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=self.root, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            np.save(fh, cube.astype(np.float16))
        os.replace(tmp, self.root / f"{key}.npy")
