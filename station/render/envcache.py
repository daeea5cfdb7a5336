"""Disk cache of prefiltered cube maps, keyed by environment content hash, exponent and sizes.

The cache directory is whatever the caller passes, else ``$CACAD_CACHE_DIR``, else
``~/.cache/cacad``; prefiltered maps go under ``<dir>/prefilter/``. Nothing is kept at module level:
each :class:`PrefilterCache` is an explicit object. Files are ``.npy`` written atomically (temporary
name, then rename), so concurrent writers never leave a half-written entry; an entry that fails to load
is treated as a miss and rewritten. The lobe maps are stored as float16 (the renderers then read them
rounded so, computed or cached); the clear coat's coat-transmitted diffuse maps (:meth:`coat_key`) as
float32, as is each environment's diffuse map (:meth:`diffuse_key`), so a cached map equals the freshly
summed one exactly.
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

    @staticmethod
    def diffuse_key(env_hash: str, out_size: int, src_size: int, engine: str) -> str:
        """File stem for the diffuse map (exponent 1, ``station.render.prefilter.prefilter_basis``) of the
        environment *env_hash*: faces of *out_size* texels summed from a source cube of *src_size* by
        *engine* (gl | numpy)."""
        return f"{env_hash[:40]}-diffuse-o{out_size}-s{src_size}-{engine}-v{CACHE_VERSION}"

    @staticmethod
    def coat_key(env_hash: str, coat_index: float, out_size: int, src_size: int, engine: str) -> str:
        """File stem for one coat-transmitted diffuse map (``station.render.prefilter.coat_diffuse_map``)
        of the environment *env_hash* under a clear coat of refractive index *coat_index*: faces of
        *out_size* texels summed from a source cube of *src_size* by *engine* (gl | numpy)."""
        return f"{env_hash[:40]}-coat{float(coat_index)!r}-o{out_size}-s{src_size}-{engine}-v{CACHE_VERSION}"

    def get(self, key: str, shape: tuple[int, ...] | None = None) -> np.ndarray | None:
        """The cached cube (6, S, S, 3) float32, or None on a miss, an unreadable entry or, with *shape*,
        an entry of another shape (each then summed again and rewritten)."""
        path = self.root / f"{key}.npy"
        try:
            cube = np.load(path).astype(np.float32)
        except (OSError, ValueError):
            return None
        return None if shape is not None and cube.shape != shape else cube

    def put(self, key: str, cube: np.ndarray, dtype: type[np.floating] = np.float16) -> None:
        """Store *cube* as *dtype* (float16, or float32 for an exact copy; atomic rename)."""
        self.root.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=self.root, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            np.save(fh, cube.astype(dtype))
        os.replace(tmp, self.root / f"{key}.npy")
