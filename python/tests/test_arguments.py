"""Arguments of the right type whose values the engine cannot take raise the package's
own errors, whose messages name the argument and show the value cut down: ints beyond
64 bits, strs with a lone surrogate (which UTF-8 cannot encode), floats that are not
finite. Arguments of the wrong type stay `TypeError`s."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

import coherent
from coherent import _coherent
from conftest import DEMO

# The robot dog of the demo task, and an action of it that the rules refuse.
DOG = 13
GRAB = "[grab] <mug>(7)"


@pytest.fixture()
def env() -> coherent.Env:
    return coherent.Env(coherent.load_tasks(DEMO)[0])


@pytest.fixture(scope="module")
def line(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """One line of a results file, as `coherent.report` takes it."""
    out = tmp_path_factory.mktemp("line") / "results.jsonl"
    coherent.bench(coherent.load_tasks(DEMO), ["optimal"], out=out)
    [first] = _coherent.read_results(out)
    return first


def test_argument_error_is_a_coherent_value_error() -> None:
    assert issubclass(coherent.ArgumentError, coherent.CoherentError)
    assert issubclass(coherent.ArgumentError, ValueError)


@pytest.mark.parametrize("robot", [2**63, -(2**63) - 1, 2**70])
@pytest.mark.parametrize("method", ["observe", "actions", "why_not", "step"])
def test_a_robot_id_beyond_64_bits_is_no_robot(env: coherent.Env, method: str, robot: int) -> None:
    args = (robot, GRAB) if method in ("why_not", "step") else (robot,)
    with pytest.raises(coherent.UnknownRobotError) as info:
        getattr(env, method)(*args)
    assert str(info.value) == (
        f"robot={robot}: no node id is that large; the robots of task demo-apartment/0 are "
        "6 (robot arm), 11 (quadrotor), 13 (robot dog)"
    )


@pytest.mark.parametrize("method", ["why_not", "step"])
def test_an_action_with_a_lone_surrogate_does_not_parse(env: coherent.Env, method: str) -> None:
    action = GRAB + "\ud800"
    before = env.graph()
    with pytest.raises(coherent.ActionParseError) as info:
        getattr(env, method)(DOG, action)
    assert str(info.value) == (
        r"cannot parse action '[grab] <mug>(7)\ud800': '\ud800' at index 15 is a lone surrogate, not a character"
    )
    assert info.value.action == action
    assert info.value.reason == r"'\ud800' at index 15 is a lone surrogate, not a character"
    assert env.graph() == before
    # The same action without it is refused by the rules, not raised.
    assert env.step(DOG, GRAB)[0] is False


def test_a_long_value_is_cut_down_in_the_message(env: coherent.Env) -> None:
    action = "\ud800" + "x" * 10_000
    with pytest.raises(coherent.ActionParseError) as info:
        env.step(DOG, action)
    # The repr's first 40 characters and its last 16.
    shown = str(info.value).split(": ")[0]
    assert shown == "cannot parse action '\\ud800" + "x" * 33 + "..." + "x" * 15 + "'"


def test_arguments_of_the_wrong_type_stay_type_errors(env: coherent.Env) -> None:
    with pytest.raises(TypeError, match="argument 'robot'"):
        env.actions("13")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'robot'"):
        env.step(13.0, GRAB)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'action'"):
        env.step(DOG, b"[grab] <mug>(7)")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="argument 'action'"):
        env.why_not(DOG, None)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("wall_ms", math.inf, r"lines[1]['wall_ms']=inf: not a finite number"),
        ("wall_ms", -math.inf, r"lines[1]['wall_ms']=-inf: not a finite number"),
        ("steps", 2**64, r"lines[1]['steps']=18446744073709551616: an int beyond the 64 bits of JSON numbers"),
        ("scene", "env\udc80", r"lines[1]['scene']='env\udc80': '\udc80' at index 3 is a lone surrogate, not a character"),
        ("backend", {"kind\ud800": 1}, r"lines[1]['backend']['kind\ud800']='kind\ud800': '\ud800' at index 4 is a lone surrogate, not a character"),
    ],
)
def test_results_lines_json_cannot_hold(line: dict[str, Any], field: str, value: Any, message: str) -> None:
    bad = {**line, field: value}
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.report([line, bad])
    assert str(info.value) == message


def test_a_results_line_key_of_the_wrong_type(line: dict[str, Any]) -> None:
    with pytest.raises(TypeError, match=r"^lines\[0\]\[1\]: a key that is not a string$"):
        coherent.report([{**line, 1: "x"}])  # type: ignore[dict-item]


@pytest.mark.parametrize("by", ["table", ""])
def test_plot_table_by(by: str) -> None:
    plot = pytest.importorskip("coherent.plot")
    with pytest.raises(coherent.ArgumentError) as info:
        plot.table([], by=by)  # type: ignore[arg-type]
    assert str(info.value) == f'by={by!r}: expected "type" or "scene"'


def test_gym_reset_seed(env: coherent.Env) -> None:
    gym = pytest.importorskip("coherent.gym")
    genv = gym.CoherentEnv(env.task)
    with pytest.raises(coherent.ArgumentError, match=r"^seed=-1: expected an int from 0$"):
        genv.reset(seed=-1)
    with pytest.raises(TypeError):
        genv.reset(seed=1.5)  # type: ignore[arg-type]
    genv.reset(seed=2**70)
    assert genv.env.seed == 2**70 % 2**64


def test_gym_step_arguments(env: coherent.Env) -> None:
    gym = pytest.importorskip("coherent.gym")
    genv = gym.CoherentEnv(env.task)
    genv.reset()
    with pytest.raises(coherent.UnknownRobotError, match="robot=18446744073709551616: no node id"):
        genv.step((2**64, GRAB))
    with pytest.raises(coherent.ActionParseError):
        genv.step((DOG, GRAB + "\udfff"))
    # A float is no robot id: not rounded, and NaN is no ValueError.
    for robot in (13.0, math.nan):
        with pytest.raises(TypeError):
            genv.step((robot, GRAB))
    assert genv.steps == 0


# ---------------------------------------------------------------------------------------
# The arguments of the module's functions (crates/coherent-py/src/args.rs): paths, ints
# out of range, floats that are not finite, text that is not text, choices.

LONE = r"'\ud800' at index {} is a lone surrogate, not a character"
U32 = 2**32 - 1
U64 = 2**64 - 1
# The most permits a (tokio) semaphore holds: requests or episodes in flight at once.
PERMITS = 2**61 - 1
LOCAL = "http://127.0.0.1:9/v1"


@pytest.fixture(scope="module")
def demo() -> coherent.Task:
    return coherent.load_tasks(DEMO)[0]


@pytest.fixture(scope="module")
def transcript(demo: coherent.Task, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return coherent.run(demo, "optimal", out=tmp_path_factory.mktemp("runs")).path


@pytest.fixture()
def in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The current folder, an empty one: nothing may be written there."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _path_calls(demo: coherent.Task, transcript: Path, tmp: Path) -> dict[str, tuple[str, Any]]:
    """Each path argument: its name, and a call that passes a value as it."""
    bench = coherent.bench
    return {
        "load_tasks": ("path", lambda p: coherent.load_tasks(p)),
        "read_tasks": ("path", lambda p: coherent.read_tasks(p)),
        "load_episode": ("path", lambda p: coherent.load_episode(p)),
        "read_results": ("path", lambda p: _coherent.read_results(p)),
        "results": ("path", lambda p: coherent.results(p)),
        "replay": ("transcript", lambda p: coherent.replay(p, out=tmp)),
        "replay out": ("out", lambda p: coherent.replay(transcript, out=p)),
        "run out": ("out", lambda p: coherent.run(demo, "optimal", out=p)),
        "bench out": ("out", lambda p: bench([demo], ["optimal"], out=p)),
        "bench replay_from": (
            "replay_from",
            lambda p: bench([demo], ["optimal"], backend="replay", replay_from=p, out=tmp / "r.jsonl"),
        ),
        "bench tasks": ("path", lambda p: bench(p, ["optimal"], out=tmp / "r.jsonl")),
        "select": ("subset", lambda p: coherent.select([demo], p)),
    }


PATH_CALLS = [
    "load_tasks", "read_tasks", "load_episode", "read_results", "results", "replay", "replay out",
    "run out", "bench out", "bench replay_from", "bench tasks", "select",
]  # fmt: skip


@pytest.mark.parametrize("call", PATH_CALLS)
def test_a_path_with_a_lone_surrogate(
    call: str, demo: coherent.Task, transcript: Path, in_tmp: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    name, function = _path_calls(demo, transcript, tmp_path_factory.mktemp("out"))[call]
    # It was a PanicException (a BaseException) from PyO3's own conversion.
    with pytest.raises(coherent.ArgumentError) as info:
        function("x\ud800")
    assert str(info.value) == f"{name}='x\\ud800': " + LONE.format(1)
    with pytest.raises(coherent.ArgumentError) as info:
        function(Path("runs") / "x\ud800")
    assert str(info.value) == f"{name}=PosixPath('runs/x\\ud800'): " + LONE.format(6)
    assert list(in_tmp.iterdir()) == []


def test_a_path_of_the_wrong_type_or_an_escaped_byte(demo: coherent.Task, tmp_path: Path) -> None:
    with pytest.raises(TypeError, match="^argument 'path': expected str, bytes or os.PathLike object, not int$"):
        coherent.load_tasks(3)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^argument 'out':"):
        coherent.run(demo, "optimal", out=None)  # type: ignore[arg-type]
    # A surrogate escaping a byte (a file name that is not UTF-8) is a name like any other.
    with pytest.raises(coherent.TaskFormatError, match="No such file"):
        coherent.load_tasks(tmp_path / "x\udcff.json")
    episode = coherent.run(demo, "optimal", out=tmp_path / "runs\udcff")
    assert episode.path.parent == tmp_path / "runs\udcff"
    # A subset that is neither a name, a path nor pairs.
    with pytest.raises(TypeError, match="^subset: expected"):
        coherent.select([demo], b"all")  # type: ignore[arg-type]


def test_cli_main_argv(tmp_path: Path) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.cli_main(["coherent", "plan", "x\ud800"])
    assert str(info.value) == "argv[2]='x\\ud800': " + LONE.format(1)
    with pytest.raises(TypeError, match="^argument 'argv': Can't extract `str` to `Vec`$"):
        coherent.cli_main("coherent plan")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^argument 'argv': expected str, bytes or os.PathLike object, not int$"):
        coherent.cli_main(["coherent", 3])  # type: ignore[list-item]
    # An escaped byte reaches the command line as that byte: the file is missing.
    assert coherent.cli_main(["coherent", "plan", str(tmp_path / "x\udcff.json")]) == 2


def _int_calls(demo: coherent.Task, tmp: Path) -> dict[str, tuple[str, int, Any]]:
    """Each unsigned int argument: its name, its largest value, and a call that passes a
    value as it."""

    def llm(**kwargs: Any) -> coherent.LLM:
        return coherent.LLM(base_url=LOCAL, model="m", **kwargs)

    def bench(**kwargs: Any) -> Any:
        return coherent.bench([demo], ["optimal"], out=tmp / "r.jsonl", **kwargs)

    def run(**kwargs: Any) -> coherent.Episode:
        return coherent.run(demo, "optimal", out=tmp, **kwargs)

    return {
        "plan max_states": ("max_states", U64, lambda v: coherent.plan(demo, max_states=v)),
        "validate max_states": ("max_states", U64, lambda v: coherent.validate(demo, max_states=v)),
        "run max_states": ("max_states", U64, lambda v: run(max_states=v)),
        "run history": ("history", U64, lambda v: run(history=v)),
        "run max_steps": ("max_steps", U32, lambda v: run(max_steps=v)),
        "run seed": ("seed", U64, lambda v: run(seed=v)),
        "bench max_states": ("max_states", U64, lambda v: bench(max_states=v)),
        "bench history": ("history", U64, lambda v: bench(history=v)),
        "bench seeds": ("seeds", U32, lambda v: bench(seeds=v)),
        "bench concurrency": ("concurrency", PERMITS, lambda v: bench(concurrency=v)),
        "LLM seed": ("seed", U64, lambda v: llm(seed=v)),
        "LLM max_retries": ("max_retries", U32, lambda v: llm(max_retries=v)),
        "LLM concurrency": ("concurrency", PERMITS, lambda v: llm(concurrency=v)),
        "LLM max_response_bytes": ("max_response_bytes", U64, lambda v: llm(max_response_bytes=v)),
    }


INT_CALLS = [
    "plan max_states", "validate max_states", "run max_states", "run history", "run max_steps", "run seed",
    "bench max_states", "bench history", "bench seeds", "bench concurrency", "LLM seed", "LLM max_retries",
    "LLM concurrency", "LLM max_response_bytes",
]  # fmt: skip


@pytest.mark.parametrize("call", INT_CALLS)
def test_an_int_out_of_range(call: str, demo: coherent.Task, tmp_path: Path) -> None:
    name, largest, function = _int_calls(demo, tmp_path)[call]
    # They were OverflowErrors.
    for value in (-1, largest + 1, 2**70, -(2**70)):
        with pytest.raises(coherent.ArgumentError) as info:
            function(value)
        assert str(info.value) == f"{name}={value}: out of range: 0 to {largest}"
    with pytest.raises(TypeError, match=f"^argument '{name}': 'float' object cannot be interpreted as an integer$"):
        function(1.0)
    assert list(tmp_path.iterdir()) == []


def test_the_largest_ints_are_taken(demo: coherent.Task, tmp_path: Path) -> None:
    # A concurrency beyond the permits was a PanicException.
    llm = coherent.LLM(base_url=LOCAL, model="m", seed=U64, max_retries=U32, concurrency=PERMITS, max_response_bytes=U64)
    assert llm.seed == U64
    assert coherent.plan(demo, max_states=U64)["optimal_steps"] == 22
    assert coherent.validate(demo, max_states=U64) == []
    episode = coherent.run(demo, "pefa", history=U64, max_steps=U32, seed=U64, max_states=U64, out=tmp_path)
    assert (episode.success, episode.max_steps, episode.header["seed"]) == (True, U32, U64)
    frame = coherent.bench([demo], ["pefa"], history=U64, concurrency=PERMITS, max_states=U64, out=tmp_path / "r.jsonl")
    assert list(frame["success"]) == [True]


NOT_FINITE = [math.nan, math.inf, -math.inf, 10**400]


def _why(value: float) -> str:
    return "too large for a float" if isinstance(value, int) else "not a finite number"


def _shown(value: Any) -> str:
    """`repr(value)` as messages show it: cut to its first 40 and last 16 characters."""
    r = repr(value)
    return r if len(r) <= 59 else f"{r[:40]}...{r[-16:]}"


def _id(value: Any) -> str:
    return "10**400" if value == 10**400 else repr(value)


@pytest.mark.parametrize("value", [*NOT_FINITE, 1e39, -1e39], ids=_id)
def test_llm_temperature_not_finite(value: float) -> None:
    # NaN and the infinities were taken, 10**400 an OverflowError, 1e39 an infinity.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.LLM(base_url=LOCAL, model="m", temperature=value)
    why = "out of range: at most 3.4028235e38 in magnitude" if abs(value) == 1e39 else _why(value)
    assert str(info.value) == f"temperature={_shown(value)}: {why}"
    assert coherent.LLM(base_url=LOCAL, model="m", temperature=2).temperature == 2.0
    with pytest.raises(TypeError, match="^argument 'temperature':"):
        coherent.LLM(base_url=LOCAL, model="m", temperature="hot")  # type: ignore[arg-type]


@pytest.mark.parametrize("name", ["connect_timeout", "read_timeout", "timeout"])
@pytest.mark.parametrize("value", [*NOT_FINITE, -1.0, 1e300], ids=_id)
def test_llm_timeout_out_of_range(name: str, value: float) -> None:
    # They were BackendErrors naming the command line's flag (--connect-timeout) or
    # OverflowErrors.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.LLM(base_url=LOCAL, model="m", **{name: value})
    why = _why(value) if value in NOT_FINITE else "out of range: 0 to 18446744073709551615 seconds"
    assert str(info.value) == f"{name}={_shown(value)}: {why}"
    assert coherent.LLM(base_url=LOCAL, model="m", **{name: 0}).model == "m"


@pytest.mark.parametrize("value", NOT_FINITE, ids=_id)
def test_sim_errors_rate_not_finite(value: float, demo: coherent.Task, tmp_path: Path) -> None:
    # NaN was a ValueError, 10**400 an OverflowError.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.run(demo, sim_errors={"hallucinate": 0.1, "all": value}, out=tmp_path)
    assert str(info.value) == f"sim_errors['all']={_shown(value)}: {_why(value)}"
    with pytest.raises(coherent.ArgumentError, match=r"^sim_errors\['all'\]="):
        coherent.bench([demo], ["pefa"], backend="simulated", sim_errors={"all": value}, out=tmp_path / "r.jsonl")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        # UnicodeEncodeErrors.
        ("all=0.1\ud800", "sim_errors='all=0.1\\ud800': " + LONE.format(7)),
        ({"all\ud800": 0.1}, "sim_errors['all\\ud800']='all\\ud800': " + LONE.format(3)),
        # Taken as two kinds.
        ({"all=1,hallucinate": 0.1}, "sim_errors['all=1,hallucinate']='all=1,hallucinate': not an error kind"),
        # The engine's own refusals: ValueErrors that were no CoherentError.
        ("typos=0.1", 'sim_errors: "typos" is not an error kind'),
        ({"all": 2}, 'sim_errors: "all=2": the rate must be a number from 0 to 1'),
    ],
    ids=["str", "key", "two kinds", "unknown kind", "rate"],
)
def test_sim_errors_refused(spec: Any, message: str, demo: coherent.Task, tmp_path: Path) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.run(demo, sim_errors=spec, out=tmp_path)
    assert str(info.value).startswith(message)
    assert list(tmp_path.iterdir()) == []


def test_sim_errors_of_the_wrong_type(demo: coherent.Task, tmp_path: Path) -> None:
    with pytest.raises(TypeError, match=r"^sim_errors\[1\]: expected a str, not int$"):
        coherent.run(demo, sim_errors={1: 0.1}, out=tmp_path)  # type: ignore[dict-item]
    with pytest.raises(TypeError, match="^must be real number, not str$"):
        coherent.run(demo, sim_errors={"all": "0.1"}, out=tmp_path)  # type: ignore[dict-item]


def test_parse_action_lone_surrogate() -> None:
    # A UnicodeEncodeError.
    with pytest.raises(coherent.ActionParseError) as info:
        coherent.parse_action("[grab] \ud800")
    assert info.value.action == "[grab] \ud800"
    assert info.value.reason == LONE.format(7)
    with pytest.raises(TypeError, match="^argument 'text':"):
        coherent.parse_action(b"[grab] <mug>(7)")  # type: ignore[arg-type]


@pytest.mark.parametrize("name", ["base_url", "model"])
def test_llm_text_lone_surrogate(name: str) -> None:
    # UnicodeEncodeErrors.
    kwargs = {"base_url": LOCAL, "model": "m", name: "m\ud800"}
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.LLM(**kwargs)
    assert str(info.value) == f"{name}='m\\ud800': " + LONE.format(1)


@pytest.mark.parametrize(
    ("key", "why"),
    [
        ("sk-SECRET-\ud800", LONE.format(10)),
        ("", "no key in it; leave api_key out (None) for none"),
        (" \t", "no key in it; leave api_key out (None) for none"),
    ],
)
def test_llm_api_key_hidden(key: str, why: str) -> None:
    # A UnicodeEncodeError (its message showing the key), or taken.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.LLM(base_url=LOCAL, model="m", api_key=key)
    assert str(info.value) == f"api_key=[hidden]: {why}"
    assert "SECRET" not in repr(info.value.args)
    assert coherent.LLM(base_url=LOCAL, model="m", api_key=None).has_api_key is False


@pytest.mark.parametrize(("value", "why"), [("\ud800", LONE.format(0)), ("yaml", 'expected "json_schema", "json_object" or "text"')])
def test_an_unknown_llm_format_is_an_argument_error_naming_the_formats(value: str, why: str) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.LLM(base_url=LOCAL, model="m", format=value)  # type: ignore[arg-type]
    assert str(info.value) == f"format={value!r}: {why}"


@pytest.mark.parametrize(("value", "why"), [("\ud800", LONE.format(0)), ("html", 'expected "markdown", "csv" or "json"')])
def test_report_text_format(value: str, why: str) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        _coherent.report_text([], value)  # type: ignore[arg-type]
    assert str(info.value) == f"format={value!r}: {why}"


@pytest.mark.parametrize(("value", "why"), [("\ud800", LONE.format(0)), ("41", 'expected None or "40"')])
def test_benchmark_subset(value: str, why: str) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        _coherent.benchmark_tasks(value)  # type: ignore[arg-type]
    assert str(info.value) == f"subset={value!r}: {why}"


def test_a_method_name_that_is_no_text_is_refused_by_run(demo: coherent.Task, tmp_path: Path) -> None:
    # A UnicodeEncodeError.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.run(demo, "pefa\ud800", out=tmp_path)
    assert str(info.value) == "method='pefa\\ud800': " + LONE.format(4)
    with pytest.raises(TypeError, match="^argument 'method':"):
        coherent.run(demo, 3, out=tmp_path)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        # ValueErrors that were no CoherentError.
        ({"method": "pefa2"}, 'unknown method "pefa2"; the methods: pefa, '),
        ({"llm": True, "sim_errors": "all=0.1"}, "simulated errors are for the simulated backend: leave out the endpoint"),
    ],
    ids=["method", "llm and sim_errors"],
)
def test_run_refuses_unusable_arguments_before_writing(kwargs: dict[str, Any], message: str, demo: coherent.Task, tmp_path: Path) -> None:
    if kwargs.get("llm"):
        kwargs = {**kwargs, "llm": coherent.LLM(base_url=LOCAL, model="m")}
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.run(demo, **kwargs, out=tmp_path)
    assert str(info.value).startswith(message)
    assert list(tmp_path.iterdir()) == []


def test_a_method_name_that_is_no_text_is_refused_by_bench_before_writing(demo: coherent.Task, tmp_path: Path) -> None:
    # A UnicodeEncodeError.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.bench([demo], ["pefa", "cmrs\ud800"], out=tmp_path / "r.jsonl")
    assert str(info.value) == "methods[1]='cmrs\\ud800': " + LONE.format(4)
    with pytest.raises(TypeError, match="^argument 'methods': Can't extract `str` to `Vec`$"):
        _coherent.run_bench([demo], "pefa", out=tmp_path / "r.jsonl")  # type: ignore[arg-type]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("backend", ["\ud800", "openai", 3], ids=repr)
def test_an_unknown_bench_backend_names_the_backends(backend: Any, demo: coherent.Task, tmp_path: Path) -> None:
    # ValueErrors that were no CoherentError.
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.bench([demo], ["pefa"], backend=backend, out=tmp_path / "r.jsonl")
    assert str(info.value) == f'backend={backend!r}: expected "builtin", "simulated", "replay" or an LLM'


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        # ValueErrors that were no CoherentError.
        ({"methods": ["nope"]}, 'unknown method "nope"; the methods: pefa, '),
        ({"methods": []}, "methods: name at least one method"),
        ({"seeds": 0}, "seeds must be at least 1"),
        ({"tasks": []}, "tasks: no tasks to run"),
        ({"sim_errors": "all=0.1"}, 'sim_errors needs backend="simulated"'),
        ({"backend": "replay"}, 'backend="replay" needs replay_from=, an earlier results file'),
        ({"replay_from": "a.jsonl"}, 'replay_from needs backend="replay"'),
    ],
    ids=["unknown method", "no methods", "no seeds", "no tasks", "sim_errors", "replay", "replay_from"],
)
def test_bench_refuses_unusable_arguments_before_writing(kwargs: dict[str, Any], message: str, demo: coherent.Task, tmp_path: Path) -> None:
    arguments = {"tasks": [demo], "methods": ["pefa"], **kwargs}
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.bench(**arguments, out=tmp_path / "r.jsonl")
    assert str(info.value).startswith(message)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("call", ["run", "replay", "bench"])
def test_an_empty_out(call: str, demo: coherent.Task, transcript: Path, in_tmp: Path) -> None:
    # run and replay wrote their transcripts into the current folder.
    calls = {
        "run": lambda: coherent.run(demo, "optimal", out=""),
        "replay": lambda: coherent.replay(transcript, out=""),
        "bench": lambda: coherent.bench([demo], ["optimal"], out=""),
    }
    with pytest.raises(coherent.ArgumentError) as info:
        calls[call]()
    assert str(info.value) == "out='': an empty path"
    assert list(in_tmp.iterdir()) == []


def test_out_the_current_folder(demo: coherent.Task, in_tmp: Path) -> None:
    # Said so, the current folder is one.
    assert coherent.run(demo, "optimal", out=".").path.parent == Path(".")


@pytest.mark.parametrize(
    ("subset", "message"),
    [
        # TypeErrors, as for any pair that is not (str, int).
        ([("demo-apartment", 0), ("demo-apartment", 2**63)], "subset[1][1]=9223372036854775808: beyond the 64 bits of task ids"),
        ([("demo\ud800", 0)], "subset[0][0]='demo\\ud800': " + LONE.format(4)),
    ],
    ids=["task_id", "scene"],
)
def test_select_pairs_refused(subset: list[tuple[str, int]], message: str, demo: coherent.Task) -> None:
    with pytest.raises(coherent.ArgumentError) as info:
        coherent.select([demo], subset)
    assert str(info.value) == message


def test_select_two_tasks_alike(demo: coherent.Task) -> None:
    # A ValueError that was no CoherentError.
    with pytest.raises(coherent.ArgumentError, match='^tasks: two tasks with scene "demo-apartment" and task_id 0'):
        coherent.select([demo, demo], "all")


def test_select_pairs_taken(demo: coherent.Task) -> None:
    for wrong in ([("demo-apartment", "0")], [(0, 0)], [("demo-apartment",)], [["demo-apartment", 0]], 40):
        with pytest.raises(TypeError, match="^subset: expected"):
            coherent.select([demo], wrong)  # type: ignore[arg-type]
    # Ints of other types that are ints (numpy's, from a DataFrame) are task ids.
    numpy = pytest.importorskip("numpy")
    chosen, missing = coherent.select([demo], [("demo-apartment", numpy.int64(0)), ("demo-apartment", -(2**63))])
    assert [t.task_id for t in chosen] == [0]
    assert missing == [("demo-apartment", -(2**63))]


def test_results_line_that_is_no_result(line: dict[str, Any]) -> None:
    # A ValueError that was no CoherentError.
    bad = {k: v for k, v in line.items() if k != "status"}
    with pytest.raises(coherent.ArgumentError, match="^results line 1: missing field `status`"):
        coherent.report([line, bad])
