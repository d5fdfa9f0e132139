"""The optional dependencies, installed by the package's extras (pyproject.toml): planning,
stepping and running need none of them; DataFrames, tables and figures need
the ``analysis`` extra, the Gymnasium environment the ``gym`` extra, the PettingZoo
environment the ``marl`` extra, a Ray cluster the ``ray`` extra. The distribution is ``coherent-robots`` (the import name is
``coherent``); from a checkout, ``pip install ".[analysis]"`` installs an extra, and
where the package is installed already, its packages themselves do (the messages name
them, with the versions the package's metadata requires)."""

from __future__ import annotations

import importlib.metadata
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

# The distribution's name on the package index.
DISTRIBUTION = "coherent-robots"

# The packages each extra brings, whose import errors it explains.
_PACKAGES = {
    "analysis": ("pandas", "matplotlib", "numpy"),
    "gym": ("gymnasium", "numpy"),
    "marl": ("pettingzoo", "gymnasium", "numpy"),
    "ray": ("ray",),
}


def install(extra: str) -> str:
    """Commands that install ``extra``: its packages as the installed package's metadata
    requires them, and the extra from a checkout of the repository."""
    try:
        requires = importlib.metadata.requires(DISTRIBUTION) or []
    except importlib.metadata.PackageNotFoundError:
        requires = []
    marker = f'extra == "{extra}"'
    wanted = [r.partition(";")[0].strip() for r in requires if marker in r.replace("'", '"')]
    packages = " ".join(f'"{r}"' for r in wanted) or " ".join(_PACKAGES[extra])
    return f'pip install {packages} (from a checkout of the repository: pip install ".[{extra}]")'


@contextmanager
def needs(what: str, extra: Literal["analysis", "gym", "marl", "ray"]) -> Iterator[None]:
    """Turns the import error of a package that ``extra`` brings, raised in the block, into
    one that says which extra to install for ``what``; any other import error passes."""
    try:
        yield
    except ImportError as e:
        package = (e.name or "").partition(".")[0]
        if package not in _PACKAGES[extra]:
            raise
        extras = ", ".join(_PACKAGES)
        raise ImportError(f"{what} needs {package}: {install(extra)}; the extras: {extras}", name=package) from e
