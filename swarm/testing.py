"""Check an exploration algorithm against the plugin contract: :func:`check_explorer`.

In the spirit of Gymnasium's ``check_env`` and PettingZoo's ``parallel_api_test``: one call runs an
explorer through small runs and hand-made observations and raises :class:`ExplorerCheckError` (an
``AssertionError``) whose message is one line naming the failed check and why, or returns a
:class:`CheckReport` of the checks passed::

    from swarm.testing import check_explorer

    def test_my_explorer_meets_the_contract():
        check_explorer("mypkg.explorer:MyExplorer")     # or the class, or its registered name

``swarm algorithms check NAME`` runs the same from the command line. The checks, in order (cheap first):

``contract``
    ``name`` is a string, ``Params`` a dataclass, ``reset``/``act`` callable with the runtime's arguments,
    the class built without arguments.
``params``
    the parameters build; an unknown key and, for every field, a value of the wrong type are one-line
    :class:`~swarm.base.errors.InvalidInput` errors; the resolved parameters are JSON and build again unchanged.
``actions``
    a small in-process run (``ticks`` ticks on a ``size`` map with ``robots`` robots) in which every
    ``act`` returns a well-formed :class:`~swarm.api.Action` (``goal``/``velocity`` None or a pair of
    finite numbers, ``messages`` a tuple, ``clear_goal`` a bool, ``debug`` None or a mapping) and leaves
    its observation as it was.
``determinism``
    the same spec run again gives a bit-identical ``deterministic_view()``.
``messages``
    every message sent is a registered message type whose first field is ``sender`` (and is the robot),
    encodes, decodes to an equal message and passes its ``validate()``; the runtime dropped none as
    malformed.
``observation``
    replayed observations of that run, with writeable maps, come out of ``act`` unchanged (a deep
    snapshot of every field, the map's bytes included).
``robustness``
    after the replay: an empty inbox, a full one (hundreds of copies of every message type the run saw
    and of the runtime's map updates), a collision, an unreachable and a blocked goal each give a
    well-formed action.
``transports``
    the run over zenoh (and any other transport asked for) gives the in-process result.

Nothing here is used by the runtime; it needs no test framework.
"""

from __future__ import annotations

import dataclasses
import inspect
import itertools
import json
import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from swarm.base.errors import InvalidInput, one_line, short_repr, shorten
from swarm.base.params import annotation_allows, field_annotations

from swarm.api import Action, NavStatus, NoParams, Observation, RobotInfo
from swarm.base.types import DRIVES
from swarm.plugins import explorers as registry

CHECKS = ("contract", "params", "actions", "determinism", "messages", "observation", "robustness", "transports")
"""Every check, in the order they run."""
_RUN_CHECKS = frozenset(CHECKS) - {"contract", "params"}
INBOX_COPIES = 200
"""The full inbox holds this many copies of every message type seen in the run (and of map updates)."""
MAX_CHECKED_MESSAGES = 5000
_REASON_CHARS = 200   # an explorer's own exception text is cut to this in a failure message


class ExplorerCheckError(AssertionError):
    """An explorer failed a check. The message is one line: ``ALGORITHM failed the CHECK check: WHY``.

    ``check`` names the check, ``reason`` says why, ``passed`` lists the checks passed before it."""

    def __init__(self, algorithm: str, check: str, reason: str, passed: Sequence[CheckResult] = ()) -> None:
        self.algorithm = algorithm
        self.check = check
        self.reason = reason
        self.passed = tuple(passed)
        super().__init__(one_line(f"{algorithm} failed the {check} check: {reason}"))


@dataclass(frozen=True)
class CheckResult:
    """One check passed: its name, what it verified and how long it took."""

    check: str
    detail: str
    seconds: float

    def __str__(self) -> str:
        return f"ok  {self.check:<12} {self.detail} ({self.seconds:.2f} s)"


@dataclass(frozen=True)
class CheckReport:
    """What :func:`check_explorer` verified: the checks passed, in order."""

    algorithm: str
    results: tuple[CheckResult, ...]

    @property
    def checks(self) -> tuple[str, ...]:
        return tuple(r.check for r in self.results)

    @property
    def seconds(self) -> float:
        return sum(r.seconds for r in self.results)

    def __str__(self) -> str:
        return "\n".join([*map(str, self.results), f"{self.algorithm}: {len(self.results)} checks passed "
                          f"({self.seconds:.1f} s)"])


class _Failed(Exception):
    """Internal: a check failed (turned into an ExplorerCheckError with the checks passed so far)."""

    def __init__(self, check: str, reason: str) -> None:
        super().__init__(reason)
        self.check = check
        self.reason = reason


# ----------------------------------------------------------------------------------- the checker ----
def check_explorer(explorer: type | str, *, map_kind: str = "building", size: int = 20, robots: int = 2,
                   ticks: int = 60, seed: int = 0, params: Mapping[str, Any] | None = None,
                   checks: Iterable[str] | None = None, transports: Sequence[str] = ("zenoh",),
                   spec: Mapping[str, Any] | None = None,
                   progress: Callable[[CheckResult], None] | None = None) -> CheckReport:
    """Check ``explorer`` (a class, a registered name or ``"package.module:Class"``); see the module
    docstring for the checks. Raises :class:`ExplorerCheckError` (one line) at the first check it fails.

    ``map_kind``/``size``/``robots``/``ticks``/``seed``: the small run (a 20 m building, 2 robots, 60
    ticks: a few seconds); ``params``: the algorithm's parameters for it; ``spec``: more run settings
    (e.g. ``{"radio": {"model": "global"}}``); ``checks``: which checks (default: all of :data:`CHECKS`);
    ``transports``: what the ``transports`` check compares with in-process; ``progress``: called with each
    check passed. Bad options (an unknown check, a spec the runtime refuses, parameters that do not
    build) are :class:`InvalidInput`.
    """
    wanted = _wanted(checks)
    for t in transports:
        if not isinstance(t, str) or t not in ("inprocess", "zenoh"):
            raise InvalidInput("transports", t, "'zenoh' (or 'inprocess')")
    label = explorer if isinstance(explorer, str) else getattr(explorer, "__qualname__", short_repr(explorer))
    checker = _Checker(label, wanted, progress)
    try:
        cls = checker.contract(explorer)
        name = checker.alias = _register_spy(cls)
        checker.params(cls, name, params)
        if wanted & _RUN_CHECKS:
            run_spec = {**dict(spec or {}), "seed": seed, "map": {**dict((spec or {}).get("map", {})), "kind": map_kind,
                                                                 "size": size},
                        "robots": {**dict((spec or {}).get("robots", {})), "count": robots},
                        "algorithm": {"name": name, "params": dict(params or {})},
                        "stop": {**dict((spec or {}).get("stop", {})), "max_ticks": ticks}}
            checker.runs(cls, name, run_spec, transports)
    except _Failed as failed:
        raise ExplorerCheckError(label, failed.check, failed.reason, checker.passed) from None
    finally:
        spy = _SPIES.get(checker.alias)
        if spy is not None:
            spy.recorder.release()   # the registry keeps the class: let the recorded maps go
    return CheckReport(label, tuple(checker.passed))


def _wanted(checks: Iterable[str] | None) -> frozenset[str]:
    if checks is None:
        return frozenset(CHECKS)
    if isinstance(checks, str):
        checks = (checks,)
    try:
        chosen = tuple(checks)
    except TypeError:
        raise InvalidInput("checks", checks, "a check name or a list of them: " + " | ".join(CHECKS)) from None
    for c in chosen:
        if not isinstance(c, str) or c not in CHECKS:
            raise InvalidInput("checks", c, " | ".join(CHECKS))
    return frozenset(chosen)


class _Checker:
    def __init__(self, label: str, wanted: frozenset[str], progress: Callable[[CheckResult], None] | None) -> None:
        self.label = label
        self.wanted = wanted
        self.progress = progress
        self.passed: list[CheckResult] = []
        self.alias = ""
        self._t0 = time.perf_counter()

    def done(self, check: str, detail: str) -> None:
        now = time.perf_counter()
        if check in self.wanted:
            result = CheckResult(check, detail, now - self._t0)
            self.passed.append(result)
            if self.progress is not None:
                self.progress(result)
        self._t0 = now

    # ------------------------------------------------------------------------------------ contract ----
    def contract(self, explorer: type | str) -> type:
        if isinstance(explorer, str):
            if ":" not in explorer and explorer not in registry.available():
                registry.load(explorer)  # an unknown name: the caller's mistake, InvalidInput
            try:
                cls = registry.load(explorer)
            except InvalidInput as exc:
                raise _Failed("contract", f"it does not load: {exc}") from None
        else:
            cls = explorer
        if not isinstance(cls, type):
            raise _Failed("contract", f"{short_repr(cls)} is not a class")
        name = getattr(cls, "name", None)
        if not isinstance(name, str) or not name:
            raise _Failed("contract", f"{cls.__name__}.name is {short_repr(name)}: allowed a non-empty string, "
                                      "the algorithm's name")
        params_cls = getattr(cls, "Params", NoParams)
        if not (isinstance(params_cls, type) and dataclasses.is_dataclass(params_cls)):
            raise _Failed("contract", f"{cls.__name__}.Params is {short_repr(params_cls)}: allowed a dataclass "
                                      "(frozen, with a default for every field)")
        for method in ("reset", "act"):
            if not callable(getattr(cls, method, None)):
                raise _Failed("contract", f"{cls.__name__} has no {method}() method")
        try:
            agent = cls()
        except Exception as exc:
            raise _Failed("contract", f"{cls.__name__}() raised {_exc(exc)}: the runtime builds an explorer "
                                      "without arguments (set up in reset())") from None
        robot = RobotInfo(id=0, n_robots=1, map_shape=(4, 4))
        for method, args in (("reset", (robot, None, np.random.default_rng(0))), ("act", (None,))):
            try:
                inspect.signature(getattr(agent, method)).bind(*args)
            except TypeError:
                expected = "reset(robot, params, rng)" if method == "reset" else "act(obs)"
                raise _Failed("contract", f"{cls.__name__}.{method}{inspect.signature(getattr(agent, method))} "
                                          f"cannot be called as {expected}") from None
            except ValueError:  # no signature (a builtin): nothing to say
                pass
        n = len(dataclasses.fields(params_cls))
        self.done("contract", f"name {name!r}, Params {params_cls.__name__} ({n} fields), reset/act, "
                              f"{cls.__name__}()")
        return cls

    # -------------------------------------------------------------------------------------- params ----
    def params(self, cls: type, name: str, params: Mapping[str, Any] | None) -> None:
        params_cls = getattr(cls, "Params", NoParams)
        if params:
            built = registry.build_params(name, params)  # the caller's parameters: InvalidInput is theirs
        else:
            try:
                built = registry.build_params(name, None)
            except InvalidInput as exc:
                raise _Failed("params", f"the default parameters do not build: {exc}") from None
        if not isinstance(built, params_cls):
            raise _Failed("params", f"building {params_cls.__name__} gave a {type(built).__name__}")
        if "params" not in self.wanted:
            self.done("params", "")
            return
        unknown = "__not_a_parameter__"
        _expect_refusal(name, {**dict(params or {}), unknown: 1}, f"an unknown parameter ({unknown} = 1)", "")
        hints = field_annotations(params_cls)
        checked = []
        for f in dataclasses.fields(params_cls):
            if not f.init:
                continue
            annotation = hints.get(f.name, Any)
            for wrong in _wrong_values(annotation, _default(f)):
                _expect_refusal(name, {**dict(params or {}), f.name: wrong}, f"{f.name} = {short_repr(wrong)}",
                                f" (annotated {_annotation_text(annotation)})")
            checked.append(f.name)
        try:
            resolved = registry.resolve_params(name, params)
            text = json.dumps(resolved, sort_keys=True, allow_nan=False)
        except (TypeError, ValueError) as exc:
            raise _Failed("params", f"the resolved parameters are not JSON ({_exc(exc)}): they go into the run's "
                                    "spec, so fields must be numbers, strings, booleans, lists or tables") from None
        try:
            again = json.dumps(registry.resolve_params(name, json.loads(text)), sort_keys=True)
        except InvalidInput as exc:
            raise _Failed("params", f"the resolved parameters do not build again ({exc}): a spec read back from "
                                    "its JSON must give the same run") from None
        if again != text:
            raise _Failed("params", f"the resolved parameters change when built again ({shorten(text)} -> "
                                    f"{shorten(again)}): a spec read back from its JSON must give the same run")
        fields_text = f"each of {len(checked)} fields refuses wrong-typed values" if checked else "no fields"
        self.done("params", f"an unknown key refused, {fields_text}, resolved parameters are JSON")

    # ---------------------------------------------------------------------------------------- runs ----
    def runs(self, cls: type, name: str, spec: Mapping[str, Any], transports: Sequence[str]) -> None:
        from swarm.sim.loop import Simulation
        from swarm.sim.spec import RunSpec

        run_spec = RunSpec.from_mapping(spec)  # a bad option is the caller's InvalidInput, before any run
        recorder = _SPIES[name].recorder
        recorder.start(collect=True)
        first = self._run(Simulation, run_spec, "actions")
        recorder.start(collect=False)
        n_acts = recorder.acts
        self.done("actions", f"{first.summary['ticks']} ticks x {run_spec.robots.count} robots: {n_acts} acts, "
                             "each a well-formed Action")
        if "determinism" in self.wanted:
            second = self._run(Simulation, run_spec, "determinism")
            diff = _first_difference(first.deterministic_view(), second.deterministic_view())
            if diff is not None:
                raise _Failed("determinism", f"two runs of the same spec differ at {diff}: draw every random number "
                                             "from the rng reset() gets (not Python's random, numpy's global state "
                                             "or the clock) and keep no state between instances")
            self.done("determinism", "the same spec twice: identical results")
        else:
            self.done("determinism", "")
        if "messages" in self.wanted:
            self.done("messages", _check_messages(recorder.sent, first))
        if self.wanted & {"observation", "robustness"}:
            replay = _Replay(cls, name, run_spec, recorder)
            replay.observations()
            self.done("observation", f"{n_acts} acts left their observation unchanged, and so did "
                                     f"{len(replay.steps)} replayed with writeable maps")
            if "robustness" in self.wanted:
                self.done("robustness", replay.edge_cases())
        if "transports" in self.wanted:
            for transport in transports:
                if transport == run_spec.transport:
                    continue
                other = self._run(Simulation, run_spec.replace(transport=transport), "transports")
                diff = _first_difference(_strip(first.deterministic_view()), _strip(other.deterministic_view()))
                if diff is not None:
                    failed = other.summary.get("failed_robots")
                    why = f" (robots {failed} failed: {_failure_events(other)})" if failed else ""
                    raise _Failed("transports", f"over {transport} the run differs from in-process at {diff}{why}: "
                                                "messages must round-trip the codec and act() depend only on the "
                                                "observation")
            self.done("transports", " = ".join(["inprocess", *[t for t in transports if t != "inprocess"]]) +
                      ": identical results")

    def _run(self, simulation: Any, spec: Any, check: str) -> Any:
        try:
            return simulation(spec).run()
        except _Failed:
            raise
        except Exception as exc:
            raise _Failed(check, f"the run failed: {_exc(exc)}") from None


# ----------------------------------------------------------------------------------- parameters ----
_WRONG_VALUES: tuple[Any, ...] = ("not-a-value", 1.5, True, 7, [1, 2], {"key": 1})


def _default(f: dataclasses.Field) -> Any:
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None


def _wrong_values(annotation: Any, default: Any) -> list[Any]:
    """Values the field must refuse: those of ``_WRONG_VALUES`` its annotation does not allow (a string,
    1.5 and True for an int...), or for an annotation that is not checked (``Any``, a class) the first
    one of another type than the default."""
    refused = [v for v in _WRONG_VALUES if annotation_allows(annotation, v) is False]
    if refused:
        return refused
    for value in _WRONG_VALUES:
        if type(value) is not type(default) and not (_number(value) and _number(default)):
            return [value]
    return [object()]


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _annotation_text(annotation: Any) -> str:
    if isinstance(annotation, type):
        return annotation.__name__
    return str(annotation).replace("typing.", "")


def _expect_refusal(name: str, params: Mapping[str, Any], what: str, annotated: str) -> None:
    """``params`` must be an InvalidInput of one line."""
    try:
        registry.build_params(name, params)
    except InvalidInput as exc:
        if "\n" in str(exc):
            raise _Failed("params", f"{what} gives a message of several lines") from None
        return
    raise _Failed("params", f"{what} was accepted{annotated}: annotate the field with a simple type (int, float, "
                            "bool, str, tuple[...], Mapping, X | None) or check it in __post_init__ with swarm.api's "
                            "check_int/check_float/check_bool/check_choice")


# ------------------------------------------------------------------------------------------ spy ----
_SPIES: dict[str, Any] = {}
_COUNTER = itertools.count()


def __getattr__(attr: str) -> Any:  # registry.load("swarm.testing:_spy_N") finds the spies here (PEP 562)
    try:
        return _SPIES[f"{__name__}:{attr}"]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {attr!r}") from None


class _Recorder:
    """What the spies saw in the recording run: robot 0's observations (copied) and actions, every message
    sent."""

    def __init__(self) -> None:
        self.collect = False
        self.acts = 0
        self.observations: list[Observation] = []
        self.sent: list[tuple[int, int, Any]] = []
        self.info: RobotInfo | None = None

    def start(self, collect: bool) -> None:
        self.collect = collect
        if collect:
            self.observations, self.sent, self.info, self.acts = [], [], None, 0

    def release(self) -> None:
        self.collect = False
        self.observations, self.sent = [], []


def _register_spy(cls: type) -> str:
    """A ``module:Class`` name for a wrapper of ``cls`` that checks every act and records the first run."""
    recorder = _Recorder()
    params_cls = getattr(cls, "Params", NoParams)

    class Spy:
        name = cls.name
        Params = params_cls

        def __init__(self) -> None:
            self.inner = cls()
            self.robot = 0

        def reset(self, robot: RobotInfo, params: Any, rng: np.random.Generator) -> None:
            self.robot = robot.id
            if recorder.collect and robot.id == 0:
                recorder.info = robot
            self.inner.reset(robot, params, rng)

        def act(self, obs: Observation) -> Action:
            action = _checked_act(self.inner, obs, f"robot {obs.robot_id}, tick {obs.tick}", "actions")
            if recorder.collect:
                recorder.acts += 1
                if self.robot == 0:
                    recorder.observations.append(_copy(obs))
                for m in action.messages[:MAX_CHECKED_MESSAGES - len(recorder.sent)]:
                    recorder.sent.append((self.robot, obs.tick, m))
            return action

    Spy.recorder = recorder  # type: ignore[attr-defined]
    attr = f"_spy_{next(_COUNTER)}"
    Spy.__name__ = Spy.__qualname__ = attr
    name = f"{__name__}:{attr}"
    _SPIES[name] = Spy
    return name


def _copy(obs: Observation) -> Observation:
    """The observation with a copy of its map (the runtime's view changes) and its neighbours as a tuple."""
    return dataclasses.replace(obs, known=np.array(obs.known), neighbours=tuple(obs.neighbours))


def _checked_act(agent: Any, obs: Observation, where: str, check: str) -> Action:
    """``agent.act(obs)``, failing when it raises, returns a malformed action or changes ``obs``."""
    before = _snapshot(obs)
    try:
        action = agent.act(obs)
    except ValueError as exc:
        if "read-only" in str(exc):
            raise _Failed("observation", f"act() wrote into its observation ({_exc(exc)}; {where}): the map is "
                                         "read-only, copy it to change it") from None
        raise _Failed(check, f"act() raised {_exc(exc)} ({where})") from None
    except Exception as exc:
        raise _Failed(check, f"act() raised {_exc(exc)} ({where})") from None
    changed = _changed(before, _snapshot(obs))
    if changed:
        raise _Failed("observation", f"act() changed its observation's {changed} ({where}): observations are "
                                     "read-only, copy what you change")
    problem = action_problem(action)
    if problem is not None:
        raise _Failed("actions", f"{problem} ({where})")
    return action


def action_problem(action: Any) -> str | None:
    """Why ``action`` is not a well-formed :class:`~swarm.api.Action`, or None."""
    if not isinstance(action, Action):
        return f"act() returned {type(action).__name__} {short_repr(action, 60)}, not a swarm.api.Action"
    for name, what in (("goal", "(x, y) in metres"), ("velocity", "(v m/s, omega rad/s)")):
        value = getattr(action, name)
        if value is not None and not _finite_pair(value):
            return f"Action.{name} is {short_repr(value, 60)}; allowed: None or a pair of finite numbers {what}"
    if not isinstance(action.messages, tuple):
        return f"Action.messages is a {type(action.messages).__name__}; allowed: a tuple of messages"
    if not isinstance(action.clear_goal, bool):
        return f"Action.clear_goal is {short_repr(action.clear_goal, 60)}; allowed: True or False"
    if action.debug is not None and not isinstance(action.debug, Mapping):
        return f"Action.debug is a {type(action.debug).__name__}; allowed: None or a mapping"
    if not isinstance(action.drive, str) or action.drive not in DRIVES:
        return f"Action.drive is {short_repr(action.drive, 60)}; allowed: {', '.join(map(repr, DRIVES))}"
    return None


def _finite_pair(v: Any) -> bool:
    return (isinstance(v, (tuple, list)) and len(v) == 2
            and all(_number(x) and math.isfinite(x) for x in v))


# -------------------------------------------------------------------------------- observations ----
_OBS_FIELDS = tuple(f.name for f in dataclasses.fields(Observation))


def _snapshot(obs: Any) -> dict[str, Any]:
    """A deep, comparable picture of an observation: every field by value, the map by its bytes, inbox
    messages by identity and wire bytes."""
    out: dict[str, Any] = {"attributes": tuple(sorted(vars(obs))) if hasattr(obs, "__dict__") else ()}
    for name in _OBS_FIELDS:
        v = getattr(obs, name, None)
        if name == "known" and isinstance(v, np.ndarray):
            out[name] = (id(v), v.shape, v.dtype.str, v.tobytes())
        elif name == "inbox":
            out[name] = tuple((id(m), _wire(m)) for m in v) if isinstance(v, tuple) else (id(v), short_repr(v))
        elif name == "neighbours":
            out[name] = tuple(tuple(n) for n in v)
        elif name == "nav" and dataclasses.is_dataclass(v):
            out[name] = (id(v), tuple(getattr(v, f.name) for f in dataclasses.fields(v)))
        else:
            out[name] = v
    return out


def _wire(msg: Any) -> Any:
    from swarm.comm.messages import encode

    try:
        return encode(msg)
    except Exception:
        return short_repr(msg)


def _changed(before: dict[str, Any], after: dict[str, Any]) -> str | None:
    for key, old in before.items():
        new = after[key]
        if key == "known" and old != new:
            if old[1:3] == new[1:3] and old[0] == new[0]:
                cells = int(np.count_nonzero(np.frombuffer(old[3], np.uint8) != np.frombuffer(new[3], np.uint8)))
                return f"known map, {cells} cell{'s' if cells != 1 else ''}"
            return "known map (replaced by another array)"
        if old != new:
            return "attributes" if key == "attributes" else key
    return None


class _Replay:
    """A fresh instance of the explorer fed robot 0's recorded observations (with writeable maps), then the
    edge cases."""

    def __init__(self, cls: type, name: str, spec: Any, recorder: _Recorder) -> None:
        from swarm.sim.spec import ROBOT_STREAM

        self.cls, self.name, self.spec, self.recorder = cls, name, spec, recorder
        self.agent = cls()
        info = recorder.info or RobotInfo(id=0, n_robots=spec.robots.count, map_shape=(1, 1))
        self.info = info
        rng = np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(ROBOT_STREAM, 0)))  # robot 0's
        try:
            self.agent.reset(info, registry.build_params(name, spec.algorithm.params), rng)
        except Exception as exc:
            raise _Failed("observation", f"reset() raised {_exc(exc)} (robot 0, replay)") from None
        self.steps: list[Observation] = []
        self.goal: tuple[float, float] | None = None
        self.last: Observation | None = None

    def act(self, obs: Observation, where: str, check: str) -> Action:
        action = _checked_act(self.agent, obs, where, check)
        if action.clear_goal:
            self.goal = None
        if action.goal is not None:
            self.goal = (float(action.goal[0]), float(action.goal[1]))
        self.last = obs
        return action

    def observations(self) -> None:
        for obs in self.recorder.observations:
            writeable = dataclasses.replace(obs, known=np.array(obs.known))
            self.act(writeable, f"replayed tick {obs.tick}", "observation")
            self.steps.append(writeable)

    def edge_cases(self) -> str:
        if self.last is None:
            raise _Failed("robustness", "robot 0 made no decision in the run: nothing to build edge cases from "
                                        "(give the check more ticks)")
        base = self.last
        tick = base.tick
        fresh = lambda **changes: dataclasses.replace(base, known=np.array(base.known), **changes)  # noqa: E731
        inbox, kinds = self._full_inbox(base)
        done = []
        cases = [("an empty inbox", dict(inbox=())),
                 (f"a full inbox ({len(inbox)} messages: {kinds})" if inbox else "", dict(inbox=inbox)),
                 ("a collision", dict(collided=True)),
                 ("an unreachable goal", "unreachable"),
                 ("a blocked goal", "blocked"),
                 ("an empty inbox again", dict(inbox=()))]
        for what, changes in cases:
            if not what:
                continue
            tick += 1
            if isinstance(changes, str):
                goal = self.goal or (base.pose.x, base.pose.y)
                nav = NavStatus(goal=goal, state=changes, path_length=0.0,
                                ticks_since_progress=30 if changes == "blocked" else 0)
                changes = dict(nav=nav)
            self.act(fresh(tick=tick, **changes), f"tick {tick} with {what}", "robustness")
            done.append(what.split(" (")[0])
        if not inbox:
            done.append("(no full inbox: a lone robot hears nobody)")
        return "survives " + ", ".join(done)

    def _full_inbox(self, base: Observation) -> tuple[tuple[Any, ...], str]:
        """Hundreds of copies of every message type the run saw, sent by other robots, and of the
        runtime's map updates and requests; empty for a lone robot (nobody sends it anything)."""
        from swarm.comm.messages import MapRequest, full_update

        n = self.info.n_robots
        if n < 2:
            return (), ""
        others = [r for r in range(n) if r != base.robot_id]
        by_type: dict[type, Any] = {}
        for robot, _, msg in self.recorder.sent:
            if type(msg) not in by_type or robot != base.robot_id:
                by_type[type(msg)] = msg if robot != base.robot_id else _as_sender(msg, others[0])
        for obs in self.recorder.observations:
            for msg in obs.inbox:
                by_type.setdefault(type(msg), msg)
        runtime = [full_update(others[0], 0, base.tick, np.ascontiguousarray(base.known),
                               (float(base.pose.x), float(base.pose.y), 0.0)),
                   MapRequest(sender=others[0], target=base.robot_id)]
        messages = [m for m in by_type.values() if m is not None] + runtime
        inbox = tuple(m for m in messages for _ in range(INBOX_COPIES))
        kinds = ", ".join(sorted({getattr(type(m), "message_type", type(m).__name__) for m in messages}))
        return inbox, f"{INBOX_COPIES} x {kinds}"


def _as_sender(msg: Any, sender: int) -> Any:
    """``msg`` as if ``sender`` had sent it (for a message type only robot 0 sent in the run)."""
    try:
        return dataclasses.replace(msg, sender=sender)
    except Exception:
        return None


# ------------------------------------------------------------------------------------- messages ----
def _check_messages(sent: list[tuple[int, int, Any]], result: Any) -> str:
    from swarm.comm.messages import MAX_MESSAGE_BYTES, decode, encode, registered

    types = registered()
    kinds: dict[str, int] = {}
    for robot, tick, msg in sent:
        cls = type(msg)
        where = f"robot {robot} sent a {cls.__name__} at tick {tick}"
        type_name = getattr(cls, "message_type", None)
        if not dataclasses.is_dataclass(cls) or types.get(type_name) is not cls:
            raise _Failed("messages", f"{where}: not a registered message type; declare it with "
                                      "@swarm.api.messages.message('pkg.name') on a frozen dataclass")
        fields = dataclasses.fields(cls)
        if not fields or fields[0].name != "sender":
            raise _Failed("messages", f"{where}: its first field must be 'sender'")
        if msg.sender != robot:
            raise _Failed("messages", f"{where} with sender={short_repr(msg.sender)}: a message's sender must be the "
                                      "robot sending it (the runtime drops forgeries)")
        try:
            data = encode(msg)
        except Exception as exc:
            raise _Failed("messages", f"{where} that does not encode ({_exc(exc)})") from None
        if len(data) > MAX_MESSAGE_BYTES:
            raise _Failed("messages", f"{where} of {len(data)} bytes, more than {MAX_MESSAGE_BYTES}")
        try:
            back = decode(data)
        except Exception as exc:
            raise _Failed("messages", f"{where} that its own decoding refuses ({_exc(exc)}): validate() or the "
                                      "field types reject what the robot sends") from None
        for f in fields:
            diff = _first_difference(getattr(msg, f.name), getattr(back, f.name), f"{cls.__name__}.{f.name}",
                                     strict=True)
            if diff is not None:
                raise _Failed("messages", f"{where} that does not round-trip the codec: {diff} (sent vs decoded); "
                                          "annotate tuple fields as tuple[...] and send tuples, not lists")
        kinds[type_name] = kinds.get(type_name, 0) + 1
    counts = result.summary["messages"]
    if counts.get("malformed"):
        drops = [e for e in result.events if e.get("event") == "message_dropped"]
        first = f" (first: robot {drops[0]['robot']} at tick {drops[0]['tick']}: {drops[0]['reason']})" if drops else ""
        raise _Failed("messages", f"the runtime dropped {counts['malformed']} malformed messages{first}")
    if not kinds:
        return "sends no messages of its own; none dropped as malformed"
    listed = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items()))
    return f"{listed}: registered, sender first, round-trip the codec; none dropped as malformed"


# -------------------------------------------------------------------------------------- results ----
def _strip(view: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in view.items() if k not in ("spec", "key")}


def _failure_events(result: Any) -> str:
    reasons = [f"robot {e['robot']}: {e['reason']}" for e in result.events if e.get("event") == "agent_failed"]
    return shorten("; ".join(reasons) or "no reason recorded", _REASON_CHARS)


def _first_difference(a: Any, b: Any, path: str = "the result", strict: bool = False) -> str | None:
    """Where two JSON-like values (or message fields) first differ, as ``path: a vs b``; None if equal.
    ``strict``: containers must also have the same type (a tuple is not a list)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)) or a.dtype != b.dtype \
                or a.shape != b.shape or not np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"):
            return f"{path}: {_shown(a)} vs {_shown(b)}"
        return None
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        for key in list(a) + [k for k in b if k not in a]:
            if key not in a or key not in b:
                return f"{_join(path, str(key))}: {'missing' if key not in a else _shown(a[key])} vs " \
                       f"{'missing' if key not in b else _shown(b[key])}"
            diff = _first_difference(a[key], b[key], _join(path, str(key)), strict)
            if diff is not None:
                return diff
        return None
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if (strict and type(a) is not type(b)) or len(a) != len(b):
            return f"{path}: {_shown(a)} vs {_shown(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            diff = _first_difference(x, y, f"{path}[{i}]", strict)
            if diff is not None:
                return diff
        return None
    if isinstance(a, np.generic):
        a = a.item()
    if isinstance(b, np.generic):
        b = b.item()
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return None
    if (isinstance(a, bool) != isinstance(b, bool)) or type(a) in (str, bytes) and type(a) is not type(b):
        return f"{path}: {_shown(a)} vs {_shown(b)}"
    try:
        same = bool(a == b)
    except Exception:
        same = False
    return None if same else f"{path}: {_shown(a)} vs {_shown(b)}"


def _join(path: str, key: str) -> str:
    return key if path == "the result" else f"{path}.{key}"


def _shown(v: Any) -> str:
    if isinstance(v, np.ndarray):
        return f"array {v.dtype}{list(v.shape)}"
    return short_repr(v, 60)


def _exc(exc: BaseException) -> str:
    text = str(exc)
    return f"{type(exc).__name__}: {shorten(text, _REASON_CHARS)}" if text else type(exc).__name__


__all__ = ["CHECKS", "CheckReport", "CheckResult", "ExplorerCheckError", "action_problem", "check_explorer"]
