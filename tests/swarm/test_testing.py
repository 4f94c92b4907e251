"""swarm.testing.check_explorer rejects broken explorers with a one-line reason naming the problem and
passes the plugin template; typed parameters (swarm.base.params.from_mapping, registry.build_params), the
``swarm algorithms check`` command and ``registry.distribution``."""

from __future__ import annotations

import ast
import random
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np
import pytest

from swarm.api import FREE, Action, InvalidInput, NoParams, Observation, cell_centre, cell_of, grid
from swarm.api.messages import message
from swarm.base.params import from_mapping
from swarm.cli import main
from swarm.plugins import explorers as registry
from swarm.testing import CHECKS, ExplorerCheckError, check_explorer

if TYPE_CHECKING:
    from swarm.sim.loop import Simulation  # noqa: F401  (an annotation that does not resolve at run time)

TEMPLATE = Path(__file__).resolve().parents[2] / "examples" / "plugin"
FAST = dict(ticks=30)   # the broken explorers fail early; a short run keeps the test quick


# ------------------------------------------------------------------------------ the explorers ----
class Nearest:
    """A minimal working explorer (the base of the broken ones): the nearest reachable unseen cell."""

    name = "nearest"
    Params = NoParams

    def reset(self, robot, params, rng) -> None:
        self.robot, self.rng = robot, rng

    def act(self, obs: Observation) -> Action:
        found = grid.nearest_reachable_unseen(obs.known, cell_of(obs.pose.x, obs.pose.y))
        if found is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        return Action(goal=cell_centre(*found[0]))


class UsesGlobalRandom(Nearest):
    """Wanders to random free cells drawn from Python's global ``random``, not from its rng."""

    def act(self, obs: Observation) -> Action:
        if obs.tick % 10 == 0:
            free = np.argwhere(obs.known == FREE)
            self.goal = cell_centre(*free[int(random.random() * len(free))])
        return Action(goal=self.goal)


class UsesTheClock(Nearest):
    """Seeds its own generator from the clock."""

    def reset(self, robot, params, rng) -> None:
        super().reset(robot, params, rng)
        self.rng = np.random.default_rng(time.time_ns())

    def act(self, obs: Observation) -> Action:
        if obs.tick % 10 == 0:
            free = np.argwhere(obs.known == FREE)
            self.goal = cell_centre(*free[self.rng.integers(len(free))])
        return Action(goal=self.goal)


class WritesIntoItsMap(Nearest):
    """Marks its own cell free in the observation's (read-only) map."""

    def act(self, obs: Observation) -> Action:
        obs.known[cell_of(obs.pose.x, obs.pose.y)] = FREE
        return super().act(obs)


class UnlocksItsMap(Nearest):
    """Makes the observation's map writeable and clears a cell in it."""

    def act(self, obs: Observation) -> Action:
        obs.known.flags.writeable = True
        obs.known[0, 0] = 0 if obs.known[0, 0] else 1
        return super().act(obs)


class RewritesTheTick(Nearest):
    """Changes a field of the frozen observation."""

    def act(self, obs: Observation) -> Action:
        object.__setattr__(obs, "tick", obs.tick + 1000)
        return super().act(obs)


@dataclass(frozen=True)
class LooseParams:
    patience: Any = 50   # annotated Any and never checked: "abc" gets through


class AcceptsAnything(Nearest):
    Params = LooseParams


@dataclass(frozen=True)
class UntypedCheckParams:
    patience: int = 50
    ratio: float = 0.5

    def __post_init__(self) -> None:
        if self.ratio > 1.0:
            raise ValueError("ratio must be at most 1")


class RaisesInPostInit(Nearest):
    """Its Params raise a plain ValueError: the registry turns that into a one-line InvalidInput."""

    Params = UntypedCheckParams


@dataclass(frozen=True)
class Gossip:      # a dataclass, but not declared with @message
    sender: int
    tick: int


class SendsUndeclaredMessages(Nearest):
    def act(self, obs: Observation) -> Action:
        action = super().act(obs)
        return Action(goal=action.goal, velocity=action.velocity, clear_goal=action.clear_goal,
                      messages=(Gossip(obs.robot_id, obs.tick),))


@message("tests.checker.ping")
@dataclass(frozen=True)
class Ping:
    sender: int
    path: tuple[int, ...] = field(default=())


class ForgesItsSender(Nearest):
    def act(self, obs: Observation) -> Action:
        return Action(goal=super().act(obs).goal, messages=(Ping(sender=obs.robot_id + 1),))


class SendsListsForTuples(Nearest):
    def act(self, obs: Observation) -> Action:
        return Action(goal=super().act(obs).goal, messages=(Ping(obs.robot_id, [1, 2]),))  # type: ignore[arg-type]


class ReturnsADict(Nearest):
    def act(self, obs: Observation) -> Action:
        return {"goal": (1.0, 1.0)}  # type: ignore[return-value]


class AimsAtNaN(Nearest):
    def act(self, obs: Observation) -> Action:
        return Action(goal=(float("nan"), 1.0)) if obs.tick >= 5 else super().act(obs)


class SendsAList(Nearest):
    def act(self, obs: Observation) -> Action:
        return Action(goal=super().act(obs).goal, messages=[])  # type: ignore[arg-type]


class GivesUpOnUnreachable(Nearest):
    """Never sees an unreachable goal in a short run, and crashes on one."""

    def act(self, obs: Observation) -> Action:
        if obs.nav.state == "unreachable":
            raise RuntimeError("no plan B")
        return super().act(obs)


class ChokesOnAFullInbox(Nearest):
    def act(self, obs: Observation) -> Action:
        assert len(obs.inbox) < 100, "inbox overflow"
        return super().act(obs)


class NeedsArguments(Nearest):
    def __init__(self, speed: float) -> None:
        self.speed = speed


class NoName(Nearest):
    name = None  # type: ignore[assignment]


class RememberedAcrossRuns(Nearest):
    """Keeps a count on the class: the second run starts where the first stopped."""

    calls = 0

    def act(self, obs: Observation) -> Action:
        RememberedAcrossRuns.calls += 1
        if RememberedAcrossRuns.calls % 37 == 0:
            return Action(velocity=(0.5, 1.0))
        return super().act(obs)


# ---------------------------------------------------------------------------------- rejections ----
@pytest.mark.parametrize("explorer, check, words", [
    (UsesGlobalRandom, "determinism", ["two runs of the same spec differ", "rng reset() gets"]),
    (UsesTheClock, "determinism", ["differ", "the clock"]),
    (RememberedAcrossRuns, "determinism", ["differ", "no state between instances"]),
    (WritesIntoItsMap, "observation", ["wrote into its observation", "read-only"]),
    (UnlocksItsMap, "observation", ["changed its observation's known map"]),
    (RewritesTheTick, "observation", ["changed its observation's tick"]),
    (AcceptsAnything, "params", ["patience = 'not-a-value' was accepted", "annotated Any"]),
    (SendsUndeclaredMessages, "messages", ["Gossip", "not a registered message type", "@swarm.api.messages.message"]),
    (ForgesItsSender, "messages", ["sender=1", "must be the robot sending it"]),
    (SendsListsForTuples, "messages", ["does not round-trip", "Ping.path: [1, 2] vs (1, 2)"]),
    (ReturnsADict, "actions", ["act() returned dict", "not a swarm.api.Action"]),
    (AimsAtNaN, "actions", ["Action.goal is (nan, 1.0)", "finite numbers"]),
    (SendsAList, "actions", ["Action.messages is a list", "a tuple"]),
    (GivesUpOnUnreachable, "robustness", ["RuntimeError: no plan B", "unreachable goal"]),
    (ChokesOnAFullInbox, "robustness", ["AssertionError: inbox overflow", "full inbox"]),
    (NeedsArguments, "contract", ["NeedsArguments() raised TypeError", "without arguments"]),
    (NoName, "contract", ["NoName.name is None", "non-empty string"]),
])
def test_broken_explorers_fail_with_one_line_naming_the_problem(explorer, check, words):
    with pytest.raises(ExplorerCheckError) as info:
        check_explorer(explorer, **FAST)
    err = info.value
    text = str(err)
    assert isinstance(err, AssertionError)
    assert err.check == check, text
    assert "\n" not in text and text.startswith(f"{explorer.__qualname__} failed the {check} check: "), text
    for word in words:
        assert word in text, text
    assert [r.check for r in err.passed] == list(CHECKS[:CHECKS.index(check)])[:len(err.passed)]


def test_the_plugin_template_passes_every_check(monkeypatch):
    monkeypatch.syspath_prepend(str(TEMPLATE))
    seen = []
    report = check_explorer("swarm_example_explorer:Claimer", progress=seen.append)
    assert report.checks == CHECKS and [r.check for r in seen] == list(CHECKS)
    assert "claimer.claim" in next(r.detail for r in report.results if r.check == "messages")
    assert "survives" in str(report) and report.seconds > 0


def test_the_plugin_template_uses_only_the_documented_contract():
    """The template's module imports only swarm.api; its tests add only swarm.run and swarm.testing."""
    allowed = {"swarm_example_explorer.py": {"swarm.api", "swarm.api.messages"},
               "tests/test_claimer.py": {"swarm", "swarm.api", "swarm.api.messages", "swarm.testing"}}
    for path, modules in allowed.items():
        tree = ast.parse((TEMPLATE / path).read_text(encoding="utf-8"))
        used = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module}
        used |= {a.name for node in ast.walk(tree) if isinstance(node, ast.Import) for a in node.names}
        swarm_used = {m for m in used if m.split(".")[0] == "swarm"}
        assert swarm_used and swarm_used <= modules, (path, swarm_used - modules)
        from_root = {a.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module == "swarm"
                     for a in node.names}
        attributes = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
                      and isinstance(node.value, ast.Name) and node.value.id == "swarm"}
        assert from_root | attributes <= {"run"}, (path, from_root | attributes)


def test_a_passing_explorer_with_a_subset_of_checks():
    report = check_explorer(Nearest, checks=["contract", "determinism"], robots=1, ticks=20, size=20)
    assert report.checks == ("contract", "determinism")


def test_bad_options_are_invalid_input_not_a_failed_check():
    with pytest.raises(InvalidInput, match="checks"):
        check_explorer(Nearest, checks=["speed"])
    for array in (np.array([1, 2]), np.array(["contract", "determinism"])):   # not numpy's truth-value error
        with pytest.raises(InvalidInput, match="checks"):
            check_explorer(Nearest, checks=[array])
        with pytest.raises(InvalidInput, match="transports"):
            check_explorer(Nearest, transports=[array])
    with pytest.raises(InvalidInput, match="checks"):
        check_explorer(Nearest, checks=3)
    with pytest.raises(InvalidInput, match="robots.count"):
        check_explorer(Nearest, robots=0)
    with pytest.raises(InvalidInput, match="algorithm.name"):
        check_explorer("no-such-explorer")
    with pytest.raises(InvalidInput, match="recheck_ticks"):
        check_explorer("frontier", params={"recheck_ticks": "often"})


# ------------------------------------------------------------------------- typed parameters ----
@dataclass(frozen=True)
class Typed:
    n: int = 1
    x: float = 0.5
    flag: bool = False
    label: str = "a"
    pair: tuple[float, float] = (0.0, 0.0)
    ids: tuple[int, ...] = ()
    table: Mapping[str, Any] = field(default_factory=dict)
    limit: int | None = None
    anything: Any = None
    later: Simulation | None = None   # does not resolve (TYPE_CHECKING): left unchecked


@pytest.mark.parametrize("key, value, allowed", [
    ("n", True, "an integer"), ("n", 1.0, "an integer"), ("n", "1", "an integer"),
    ("x", True, "a number"), ("x", "0.5", "a number"),
    ("flag", 1, "true or false"), ("label", 3, "a string"),
    ("pair", [1.0], "a list of 2 numbers"), ("pair", "ab", "a list of 2 numbers"), ("ids", [1, 2.5], "a list of integers"),
    ("table", [1], "a table"), ("limit", "none", "an integer or none"),
])
def test_values_are_checked_against_simple_annotations(key, value, allowed):
    with pytest.raises(InvalidInput) as info:
        from_mapping(Typed, {key: value}, prefix="p.")
    assert info.value.field == f"p.{key}" and info.value.allowed == allowed


def test_accepted_values_are_passed_on_unconverted():
    got = from_mapping(Typed, {"n": 3, "x": 2, "pair": [1, 2.5], "ids": (4, 5), "table": {"k": [1]}, "limit": None,
                               "anything": object, "later": "whatever"})
    assert got.x == 2 and type(got.x) is int, "an int for a float is kept as given (canonical specs do not change)"
    assert got.pair == [1, 2.5] and type(got.pair) is list and got.ids == (4, 5)
    assert got.anything is object and got.later == "whatever"


def test_the_classes_own_checks_speak_first():
    with pytest.raises(InvalidInput, match=r"^algorithm\.params\.recheck_ticks: got 'x'; allowed: an integer in 1\.\.100000$"):
        registry.build_params("frontier", {"recheck_ticks": "x"})


def test_an_exception_in_post_init_is_a_one_line_invalid_input_naming_the_field():
    name = f"{__name__}:RaisesInPostInit"
    with pytest.raises(InvalidInput) as info:
        registry.build_params(name, {"ratio": 2.0})
    assert info.value.field == "algorithm.params.ratio" and "ValueError: ratio must be at most 1" in str(info.value)
    with pytest.raises(InvalidInput) as info:
        registry.build_params(name, {"patience": "abc"})
    assert str(info.value) == "algorithm.params.patience: got 'abc'; allowed: an integer"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_swarm_run_with_a_wrong_typed_param_is_one_line(capsys):
    code, _, err = run(capsys, "run", "--algorithm", f"{__name__}:RaisesInPostInit", "--param", "patience=abc",
                       "--max-ticks", "2")
    assert code == 2 and err == "swarm: error: algorithm.params.patience: got 'abc'; allowed: an integer\n"
    code, _, err = run(capsys, "run", "--algorithm", f"{__name__}:RaisesInPostInit", "--param", "ratio=3",
                       "--max-ticks", "2")
    assert code == 2 and err.count("\n") == 1 and "algorithm.params.ratio: got 3" in err


# --------------------------------------------------------------------------------- the command ----
def test_algorithms_check_prints_every_check_and_exits_0(capsys):
    code, out, _ = run(capsys, "algorithms", "check", f"{__name__}:Nearest", "--ticks", "20", "--robots", "1")
    lines = out.splitlines()
    assert code == 0 and [line.split()[1] for line in lines[:-1]] == list(CHECKS)
    assert all(line.startswith("ok  ") for line in lines[:-1]) and "8 checks passed" in lines[-1]


def test_algorithms_check_failure_is_one_line_and_exits_1(capsys):
    code, out, err = run(capsys, "algorithms", "check", f"{__name__}:ReturnsADict", "--ticks", "10")
    assert code == 1 and err.count("\n") == 1
    assert err.startswith(f"FAIL {__name__}:ReturnsADict failed the actions check: act() returned dict")
    assert out.splitlines()[0].startswith("ok  contract")


def test_the_command_offers_every_check():
    from swarm.cli.run_cmd import _CHECK_NAMES

    assert _CHECK_NAMES == CHECKS


def test_algorithms_check_bad_flags_exit_2_and_the_listing_stays(capsys):
    assert run(capsys, "algorithms", "check", "greed", "--robots", "0")[0] == 2
    code, _, err = run(capsys, "algorithms", "check", "greed", "--param", "deadlock_ticks=soon")
    assert code == 2 and err.startswith("swarm: error: algorithm.params.deadlock_ticks: got 'soon'")
    code, out, _ = run(capsys, "algorithms")
    assert code == 0 and "greed  (algorithms.greed:Greed)" in out and "deadlock_ticks = 50" in out


# ------------------------------------------------------------------------------- distribution ----
def test_distribution_of_registered_and_path_algorithms():
    from importlib.metadata import version

    assert registry.distribution("greed") == ("swarm-sim", version("swarm-sim"))
    assert registry.distribution("algorithms.tnf:TNF") == ("swarm-sim", version("swarm-sim"))
    assert registry.distribution(f"{__name__}:Nearest") is None, "a test module is in no installed distribution"
    with pytest.raises(InvalidInput, match="algorithm.name"):
        registry.distribution("no-such-explorer")


def test_a_drive_that_is_not_a_string_is_named_not_a_numpy_error():
    from swarm.testing import action_problem
    from swarm.transport.inprocess import check_action

    bad = Action(goal=(1.0, 1.0), drive=np.array(["path", "runs"]))
    assert action_problem(bad).startswith("Action.drive is")
    with pytest.raises(TypeError, match="Action.drive"):
        check_action(bad, 3)
    assert action_problem(Action(goal=(1.0, 1.0), drive="runs")) is None
