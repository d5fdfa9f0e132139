"""The optional dependencies, installed by the package's extras (pyproject.toml): planning,
stepping and running need none of them; DataFrames, tables and figures need
``coherent[analysis]``, the Gymnasium environment ``coherent[gym]``, the PettingZoo
environment ``coherent[marl]``."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

# The packages each extra brings (numpy comes with all of them).
_PACKAGES = {
    "analysis": ("pandas", "matplotlib", "numpy"),
    "gym": ("gymnasium", "numpy"),
    "marl": ("pettingzoo", "gymnasium", "numpy"),
}


@contextmanager
def needs(what: str, extra: Literal["analysis", "gym", "marl"]) -> Iterator[None]:
    """Turns the import error of a package that ``extra`` brings, raised in the block, into
    one that says which extra to install for ``what``; any other import error passes."""
    try:
        yield
    except ImportError as e:
        package = (e.name or "").partition(".")[0]
        if package not in _PACKAGES[extra]:
            raise
        raise ImportError(f"{what} needs {package}: pip install 'coherent[{extra}]'", name=package) from e
