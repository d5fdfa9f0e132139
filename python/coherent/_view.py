"""``coherent.view``: an episode, two side by side, or benchmark results as one HTML page
that needs nothing else (the page of ``coherent view``), shown inline in Jupyter."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union

from . import _coherent

if TYPE_CHECKING:
    import pandas as pd

PathLike = Union[str, "os.PathLike[str]"]


class Page:
    """A page of ``coherent view``: ``html`` is the whole document (its data, script and
    style inside it; it asks nothing of any other origin). In Jupyter it shows inline, in
    a sandboxed frame; :meth:`save` writes it to open in a browser."""

    def __init__(self, html: str) -> None:
        self.html = html

    def save(self, path: PathLike) -> Path:
        """Writes the page to ``path`` and returns it."""
        out = Path(path)
        out.write_text(self.html, encoding="utf-8")
        return out

    def _repr_html_(self) -> str:
        return _coherent.framed_page(self.html)

    def __str__(self) -> str:
        return self.html

    def __repr__(self) -> str:
        return f"<coherent view page, {len(self.html)} characters>"


def view(source: Any, other: Any = None) -> Page:
    """The page of ``source``: an :class:`~coherent.Episode` or a transcript's path (the
    episode's page, as ``coherent view TRANSCRIPT`` writes it); with ``other``, a second
    episode shown beside it, stepping together, the first round where their decisions
    differ marked; a results file's path or a results DataFrame (:func:`coherent.results`,
    :func:`coherent.bench`): the index of the results, its tables, figures and episodes
    (``coherent view RESULTS -o DIR`` also writes a page per episode).

    A transcript cut in the middle of its last line shows its whole rounds, the page
    saying so. Raises :class:`~coherent.DataFileError` for a file that cannot be read
    or does not follow its format, :class:`~coherent.ArgumentError` for two episodes of
    different tasks or a results file where an episode belongs."""
    if other is None and hasattr(source, "to_dict") and hasattr(source, "columns"):
        from .analysis import _lines

        name = source.attrs.get("path", "results") if hasattr(source, "attrs") else "results"
        return Page(_coherent.results_page(_lines(source), str(name)))
    return Page(_coherent.view_page(source, other))


class ResultsAccessor:
    """``df.coherent`` on a results DataFrame: shown in Jupyter, the results page
    (:func:`view`) instead of the table; ``df.coherent.view()`` is that :class:`Page`.
    The DataFrame itself stays a plain DataFrame and shows as one."""

    def __init__(self, frame: pd.DataFrame) -> None:
        self._frame = frame

    def view(self) -> Page:
        return view(self._frame)

    def _repr_html_(self) -> str:
        return self.view()._repr_html_()


_registered = False


def register(pandas: Any) -> None:
    """Makes ``df.coherent`` available on every DataFrame (once)."""
    global _registered
    if not _registered:
        pandas.api.extensions.register_dataframe_accessor("coherent")(ResultsAccessor)
        _registered = True
