"""Where :func:`coherent.bench` runs its episodes: on this machine (``executor="local"``,
the default: the Rust harness, as ``coherent bench``) or on a Ray cluster
(``executor="ray"`` or a :class:`RayExecutor`).

On Ray the episodes run in actors (``coherent._ray_worker.EpisodeRunner``), each
through the same Rust function as the local executor's, so both write the same results
lines. The driver, this process, alone writes the results file: it resumes it, hands
out the episodes still to run, and writes each result as it comes, once. A worker that
dies takes no results with it: the episodes it was running go to a fresh actor, and the
finished ones, already written, never run again. ``docs/scale.md`` has the whole story.
"""

from __future__ import annotations

import math
import os
from collections import Counter, deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from . import _coherent
from ._coherent import LLM, CoherentError, Task
from ._extras import needs

if TYPE_CHECKING:
    from ._ray_worker import NodeEndpoints

# An episode's key: (method, scene, task_id, seed index, execution).
Key = tuple[str, str, int, int, str]


def _import_ray() -> Any:
    with needs('executor="ray"', "ray"):
        import ray
    return ray


@dataclass
class RayExecutor:
    """Runs :func:`coherent.bench`'s episodes on a Ray cluster.

    ``address``: the cluster to join (``ray.init(address=...)``, e.g. ``"auto"`` or
    ``"ray://head:10001"``); ``None`` starts a local one with ``num_cpus`` CPUs (all of
    them when ``None``). A Ray already initialised in this process is used as it is. A
    local cluster started here lives until the process ends or ``ray.shutdown()``.

    ``workers``: episode-running actors (default: one per CPU of the cluster), spread
    over the nodes; ``bench``'s ``concurrency`` episodes run at once across them.

    ``endpoint_per_node``: where each node serves its own model, the base URL(s) an
    episode on that node uses instead of the LLM's: one URL (``"http://127.0.0.1:8000/v1"``
    is each node's own server), a list, a mapping from node IP address to URL(s), or a
    function of the node's IP address (called on the node).

    ``max_attempts``: how many times one episode may lose its worker before the run
    stops with an error. ``init_args``: more keyword arguments for ``ray.init``.
    """

    address: str | None = None
    num_cpus: int | None = None
    workers: int | None = None
    endpoint_per_node: NodeEndpoints | None = None
    max_attempts: int = 3
    init_args: Mapping[str, Any] = field(default_factory=dict)

    def run(
        self,
        tasks: Sequence[Task],
        methods: Sequence[str | Callable[[Task], Any]],
        *,
        backend: str | LLM | None,
        sim_errors: str | Mapping[str, float] | None,
        replay_from: str | os.PathLike[str] | None,
        seeds: int,
        concurrency: int,
        history: int,
        max_states: int,
        max_steps: int | None,
        out: str | os.PathLike[str] | None,
        progress: Literal["bar", "lines"] | None,
        prompts: str | os.PathLike[str] | Mapping[str, str] | None,
        prices: str | os.PathLike[str] | Mapping[str, Mapping[str, Any]] | None,
        physics: bool = False,
        execution: str | Sequence[str] = "sequential",
        step_timeout: float | None = None,
    ) -> dict[str, Any]:
        """Runs the benchmark as :func:`coherent.bench` describes; returns its outcome,
        with ``resubmitted``: the episodes run again after their worker died."""
        ray = _import_ray()
        if self.endpoint_per_node is not None and not isinstance(backend, LLM):
            raise ValueError("endpoint_per_node needs an LLM backend")
        if self.max_attempts < 1:
            raise ValueError("max_attempts must be at least 1")
        ledger = _coherent._BenchLedger(
            list(tasks),
            list(methods),
            seeds=seeds,
            out=None if out is None else os.path.abspath(out),
            execution=execution,
            backend=backend,
            sim_errors=sim_errors,
            replay_from=replay_from,
            history=history,
            max_states=max_states,
            max_steps=max_steps,
            physics=physics,
            progress=progress,
            prompts=prompts,
            prices=prices,
        )
        out = os.path.abspath(ledger.out)
        pending = deque(ledger.pending())
        if not pending:
            return {**ledger.finish(interrupted=False), "resubmitted": 0}
        if not ray.is_initialized():
            if self.address is None:
                ray.init(num_cpus=self.num_cpus, include_dashboard=False, **self.init_args)
            else:
                ray.init(address=self.address, **self.init_args)
        from ._ray_worker import EpisodeRunner

        settings = {
            "backend": backend._settings() if isinstance(backend, LLM) else backend,
            "endpoint_per_node": self.endpoint_per_node,
            "sim_errors": sim_errors,
            "replay_from": None if replay_from is None else os.path.abspath(replay_from),
            "history": history,
            "max_states": max_states,
            "max_steps": max_steps,
            "physics": physics,
            "execution": execution,
            "step_timeout": step_timeout,
            "out": out,
            # A folder or a price file of this machine's, as data: the workers' machines
            # may not have them.
            **ledger.worker_settings(),
        }
        # Methods written in Python travel as Ray pickles them (by reference to an
        # importable module, by value for a class defined in a function or __main__).
        shipped = ([t.to_json() for t in tasks], list(methods))
        pool = _Pool(ray, EpisodeRunner, shipped, settings, self._workers(ray, concurrency), concurrency)
        try:
            resubmitted = pool.drain(pending, ledger, self.max_attempts)
        except BaseException:
            pool.stop()
            ledger.finish(interrupted=True)
            raise
        pool.stop()
        return {**ledger.finish(interrupted=False, orphans=resubmitted > 0), "resubmitted": resubmitted}

    def _workers(self, ray: Any, concurrency: int) -> int:
        n = self.workers or int(ray.cluster_resources().get("CPU", 1))
        return max(1, min(n, concurrency))


class _Pool:
    """The actors of a run, each running up to `slots` episodes at once, and the episodes
    in flight on them."""

    def __init__(
        self, ray: Any, runner: Any, shipped: tuple[list[str], list[Any]], settings: dict[str, Any], workers: int, concurrency: int
    ) -> None:
        self.ray = ray
        self.slots = math.ceil(concurrency / workers)
        cpus = ray.cluster_resources().get("CPU", 1)
        self.options = {
            "num_cpus": min(1.0, cpus / workers),
            "max_concurrency": self.slots,
            "scheduling_strategy": "SPREAD",
        }
        self.runner = runner
        self.args = (ray.put(shipped), settings)
        self.actors = [self._start() for _ in range(workers)]
        # An actor that cannot start (bad settings, no key on a node) says why here.
        try:
            ray.get([a.pid.remote() for a in self.actors])
        except ray.exceptions.RayActorError as e:
            self.stop()
            raise CoherentError(f"a Ray worker could not start: {e}") from e
        # ref -> (key, actor index, actor generation)
        self.in_flight: dict[Any, tuple[Key, int, int]] = {}
        self.generation = [0] * workers

    def _start(self) -> Any:
        return self.runner.options(**self.options).remote(*self.args)

    def _load(self, i: int) -> int:
        return sum(1 for _, j, g in self.in_flight.values() if j == i and g == self.generation[i])

    def _submit(self, key: Key) -> bool:
        loads = [self._load(i) for i in range(len(self.actors))]
        i = min(range(len(self.actors)), key=loads.__getitem__)
        if loads[i] >= self.slots:
            return False
        ref = self.actors[i].run.remote(key)
        self.in_flight[ref] = (key, i, self.generation[i])
        return True

    def _replace(self, i: int, generation: int) -> None:
        """A fresh actor in place of actor `i`, unless that was done since `generation`."""
        if self.generation[i] != generation:
            return
        self.ray.kill(self.actors[i], no_restart=True)
        self.actors[i] = self._start()
        self.generation[i] += 1

    def drain(self, pending: deque[Key], ledger: Any, max_attempts: int) -> int:
        """Runs every episode of `pending`, recording each result in `ledger`; returns
        how many were run again after their worker died."""
        lost: Counter[Key] = Counter()
        while pending or self.in_flight:
            while pending and self._submit(pending[0]):
                pending.popleft()
            # A timeout, so that Ctrl-C is heard.
            done, _ = self.ray.wait(list(self.in_flight), num_returns=1, timeout=0.5)
            for ref in done:
                key, i, generation = self.in_flight.pop(ref)
                try:
                    result = self.ray.get(ref)
                except self.ray.exceptions.RayActorError as e:
                    lost[key] += 1
                    if lost[key] >= max_attempts:
                        raise CoherentError(f"episode {key}: its worker died {lost[key]} times; the last: {e}") from e
                    self._replace(i, generation)
                    pending.appendleft(key)
                    continue
                except self.ray.exceptions.RayTaskError as e:
                    raise e.as_instanceof_cause() from None
                ledger.record(result)
        return sum(lost.values())

    def stop(self) -> None:
        """Ends every actor (and the episodes still running on them)."""
        for actor in self.actors:
            self.ray.kill(actor, no_restart=True)


def resolve(executor: str | RayExecutor) -> RayExecutor | None:
    """The executor `executor` names: None for the local one."""
    if isinstance(executor, RayExecutor):
        return executor
    if executor == "local":
        return None
    if executor == "ray":
        _import_ray()
        return RayExecutor()
    raise ValueError(f'executor {executor!r}: expected "local", "ray" or a RayExecutor')
