"""What the engine uses to run methods written in Python (not an API of its own; see
:func:`coherent.run`, :func:`coherent.bench` and ``docs/methods.md``).

The Rust side calls ``act`` of a method once per step, with the step's model-call
recorder in :data:`_step` (a context variable, so that :class:`coherent.LLM` files each
call under the step that made it, however many episodes run at once), on a thread of
the episode's own: a call the episode stops waiting for (Ctrl-C, the step's time limit)
is interrupted there with :class:`StepStopped` (:func:`interrupt`). A coroutine that
``act`` returns runs on one asyncio event loop, on its own thread, shared by every
episode of a run: the coroutines of concurrent episodes overlap there.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextvars
import ctypes
import importlib
import importlib.util
import os
import sys
import threading
import traceback
from collections.abc import Callable, Coroutine, Mapping
from pathlib import Path
from typing import Any

# The recorder of the step being decided, read by LLM.chat and LLM.achat.
_step: contextvars.ContextVar[Any] = contextvars.ContextVar("coherent_step", default=None)


class StepStopped(BaseException):
    """Raised inside a method's ``act`` (or its constructor) that the episode no longer
    waits for: it was stopped (Ctrl-C, SIGTERM) or the step ran out of time
    (``step_timeout``). A ``BaseException``, so that ``except Exception`` lets it through."""


def interrupt(ident: int) -> None:
    """Raises :class:`StepStopped` in the thread ``ident`` (``threading.get_ident()``) at
    its next bytecode (a call blocked in C code sees it once that returns)."""
    ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(ident), ctypes.py_object(StepStopped))


def method_name(method: Any) -> str:
    """``method.name`` when it is a string, else its class's (or function's) name."""
    name = getattr(method, "name", None)
    if isinstance(name, str):
        return name
    own = getattr(method, "__name__", None)
    return own if isinstance(own, str) else type(method).__name__


def method_settings(method: Any) -> dict[str, Any]:
    """``method.settings``: what the method declares of its own settings (a mapping of
    JSON values), recorded in each of its results lines so that results of other
    settings are not resumed or reported as its own; ``{}`` when it declares none."""
    settings = getattr(method, "settings", None)
    if settings is None:
        return {}
    if not isinstance(settings, Mapping) or not all(isinstance(k, str) for k in settings):
        raise TypeError(f"{method_name(method)}.settings: expected a dict of str keys, got {settings!r}")
    return dict(settings)


def describe(error: BaseException, tb: Any = None) -> str:
    """An exception as Python prints it: the traceback (``tb``, else its own), then the
    exception's line."""
    return "".join(traceback.format_exception(type(error), error, tb or error.__traceback__)).rstrip()


async def _with_step(coroutine: Coroutine[Any, Any, Any], recorder: Any) -> Any:
    _step.set(recorder)
    return await coroutine


class Loop:
    """One asyncio event loop on a thread of its own, started when first needed."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    def submit(
        self, coroutine: Coroutine[Any, Any, Any], recorder: Any, done: Callable[[concurrent.futures.Future[Any]], None]
    ) -> concurrent.futures.Future[Any]:
        """Runs ``coroutine`` on the loop with ``recorder`` as its step's; ``done`` gets
        the future when it ends."""
        with self._lock:
            if self._loop is None:
                self._loop = asyncio.new_event_loop()
                self._thread = threading.Thread(target=self._loop.run_forever, name="coherent-methods", daemon=True)
                self._thread.start()
            future = asyncio.run_coroutine_threadsafe(_with_step(coroutine, recorder), self._loop)
        future.add_done_callback(done)
        return future

    def close(self) -> None:
        """Cancels what still runs, stops the loop and closes it."""
        with self._lock:
            loop, thread = self._loop, self._thread
            self._loop = self._thread = None
        if loop is None or thread is None:
            return

        async def finish() -> None:
            tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            await loop.shutdown_asyncgens()

        asyncio.run_coroutine_threadsafe(finish(), loop).result()
        loop.call_soon_threadsafe(loop.stop)
        thread.join()
        loop.close()


async def _when_awaited(begin: Callable[[], Any]) -> Any:
    """Awaits the future ``begin()`` makes on the loop that awaits this coroutine: what
    ``LLM.achat`` returns when no loop runs yet (``asyncio.run(llm.achat(...))``)."""
    return await begin()


def _settle(future: asyncio.Future[Any], ok: bool, value: Any) -> None:
    """Ends an awaited model call (``LLM.achat``) unless it was cancelled meanwhile."""
    if future.done():
        return
    if ok:
        future.set_result(value)
    else:
        future.set_exception(value)


def load(spec: str) -> Any:
    """The method ``MODULE:CLASS`` names: ``CLASS`` (any callable, a dotted path inside
    the module) of an importable ``MODULE`` or of a ``.py`` file, as the ``coherent``
    command's ``--method`` and ``--methods`` take it."""
    module_name, sep, attribute = spec.rpartition(":")
    if not sep or not module_name or not attribute:
        raise ValueError(f"{spec!r}: expected MODULE:CLASS (a module or a .py file, and a class in it)")
    if module_name.endswith(".py") or os.sep in module_name or "/" in module_name:
        path = Path(module_name)
        if not path.is_file():
            raise FileNotFoundError(f"{spec!r}: no file {module_name}")
        name = f"coherent_method_{path.stem}"
        module_spec = importlib.util.spec_from_file_location(name, path)
        if module_spec is None or module_spec.loader is None:
            raise ImportError(f"{spec!r}: {module_name} cannot be imported")
        module = importlib.util.module_from_spec(module_spec)
        sys.modules[name] = module
        module_spec.loader.exec_module(module)
    else:
        # As `python -m` would find it: from the current folder first.
        if os.getcwd() not in sys.path and "" not in sys.path:
            sys.path.insert(0, os.getcwd())
        module = importlib.import_module(module_name)
    found: Any = module
    for part in attribute.split("."):
        try:
            found = getattr(found, part)
        except AttributeError:
            raise AttributeError(f"{spec!r}: {module_name} has no {attribute}") from None
    if not callable(found):
        raise TypeError(f"{spec!r}: {attribute} is not a class or a callable")
    return found
