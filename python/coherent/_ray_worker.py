"""The Ray actor that runs benchmark episodes for :class:`coherent.executors.RayExecutor`.

Imported on the driver when a run starts and on every Ray worker that hosts an actor
(this module imports Ray; ``coherent`` itself does not). Each actor holds one
``_coherent._BenchWorker``: the run's tasks and settings, a runtime and, for an
:class:`~coherent.LLM`, one HTTP client shared by the episodes it runs at once.
"""

from __future__ import annotations

import os
import socket
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Union

import ray

from . import _coherent
from ._coherent import LLM, BackendError

# `endpoint_per_node`: the base URL(s) of the node an actor runs on, by the node's IP
# address, or from a function of it (called on the node).
NodeEndpoints = Union[
    str,
    Sequence[str],
    Mapping[str, Union[str, Sequence[str]]],
    Callable[[str], Union[str, Sequence[str]]],
]


def node_urls(spec: NodeEndpoints, node_ip: str) -> list[str]:
    """The base URLs `spec` gives the node at `node_ip`."""
    if callable(spec):
        urls = spec(node_ip)
    elif isinstance(spec, Mapping):
        if node_ip not in spec:
            raise BackendError(f"endpoint_per_node names no endpoint for the node at {node_ip}")
        urls = spec[node_ip]
    else:
        urls = spec
    urls = [urls] if isinstance(urls, str) else list(urls)
    if not urls:
        raise BackendError(f"endpoint_per_node gives no endpoint for the node at {node_ip}")
    return urls


def worker_backend(backend: Any, endpoint_per_node: NodeEndpoints | None) -> Any:
    """The backend argument on this worker: a name as it is; an LLM's settings built into
    an LLM here, with this node's endpoints when `endpoint_per_node` says so, and the key
    from this node's ``OPENAI_API_KEY`` (the driver never sends it)."""
    if not isinstance(backend, dict):
        return backend
    settings = dict(backend)
    had_key = settings.pop("has_api_key")
    if endpoint_per_node is not None:
        settings["base_url"] = node_urls(endpoint_per_node, ray.util.get_node_ip_address())
    llm = LLM(**settings)
    if had_key and not llm.has_api_key:
        raise BackendError(
            f"the LLM has an API key, which is never sent to Ray workers; on {socket.gethostname()} "
            "OPENAI_API_KEY is not set: set it where `ray start` runs on every node"
        )
    return llm


@ray.remote
class EpisodeRunner:
    """Runs episodes by their key; Ray's `max_concurrency` sets how many at once."""

    def __init__(self, shipped: tuple[list[str], list[Any]], settings: dict[str, Any]) -> None:
        tasks, methods = shipped
        settings = dict(settings)
        endpoint_per_node = settings.pop("endpoint_per_node")
        settings["backend"] = worker_backend(settings["backend"], endpoint_per_node)
        self._worker = _coherent._BenchWorker(tasks, methods, **settings)

    def pid(self) -> int:
        """This actor's process id; calling it also waits until the actor is up."""
        return os.getpid()

    def run(self, key: tuple[str, str, int, int, str]) -> tuple[str, str | None]:
        """Runs the episode `(method, scene, task_id, seed, execution)`; what the driver
        records."""
        return self._worker.run(tuple(key))
