"""Claimer: a complete small explorer for swarm, the template of docs/plugins.md.

Each robot heads for the reachable unseen cell nearest by path length on its own map (the runtime drives
it there), tells the others where it goes with its own message type, and leaves the unseen cells near
the places others claimed to them. Targets the navigator reports ``unreachable`` or ``blocked`` are
skipped for a while; after a collision the robot backs off for a few ticks, turning a random way.

Copy this file, rename the class, ``name`` and the message type, and keep the rules it follows:

* it imports nothing of swarm but ``swarm.api`` (types, validators, grid helpers, messages);
* every parameter is a typed field of a frozen dataclass, checked in ``__post_init__``;
* every random number comes from the ``rng`` given to ``reset`` (runs stay bit-reproducible);
* it never changes its observation (``obs.known`` is read-only; copy it to change it);
* its message is declared with ``@message``, its first field is ``sender``, ``validate()`` refuses bad ones.

``swarm algorithms check claimer`` (once installed: ``pip install -e examples/plugin``) or
``swarm.testing.check_explorer("swarm_example_explorer:Claimer")`` checks all of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm.api import (CELL_M, UNSEEN, Action, Observation, RobotInfo, cell_centre, cell_of, check_float,
                       check_int, grid)
from swarm.api.messages import message, require_finite

LOOK_CELLS = 3   # a target is worth going to while unseen cells remain this close to it (1.5 m)


@message("claimer.claim")
@dataclass(frozen=True)
class Claim:
    """"I am heading for (x, y)" (metres). Sent once per new target; delivered to the robots the radio
    reaches at the next tick. Its encoded size counts against the radio's bandwidth."""

    sender: int
    x: float
    y: float

    def validate(self) -> None:
        """Called on every decoded Claim (messages from remote agents are untrusted bytes)."""
        require_finite("claimer.claim", x=self.x, y=self.y)


@dataclass(frozen=True)
class ClaimerParams:
    claim_radius_m: float = 3.0   # unseen cells this close to a teammate's claim are left to it
    exclude_ticks: int = 200      # a target the navigator could not reach is skipped this long
    backoff_ticks: int = 8        # reverse this long after a collision; 0 = never

    def __post_init__(self) -> None:
        check_float("claim_radius_m", self.claim_radius_m, 0.0, 100.0)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)
        check_int("backoff_ticks", self.backoff_ticks, 0, 1_000)


class Claimer:
    name = "claimer"
    Params = ClaimerParams

    def reset(self, robot: RobotInfo, params: ClaimerParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.rng = rng
        self.target: tuple[int, int] | None = None          # the cell we are heading for
        self.claims: dict[int, tuple[float, float]] = {}    # robot id -> where it said it goes
        self.excluded: dict[tuple[int, int], int] = {}      # cell -> tick until which it is skipped
        self.backoff_until = -1
        self.turn = 0.0

    def act(self, obs: Observation) -> Action:
        for msg in obs.inbox:   # teammates' claims; the runtime's MapUpdates are already merged into obs.known
            if isinstance(msg, Claim) and msg.sender != self.robot.id:
                self.claims[msg.sender] = (msg.x, msg.y)
        if obs.collided and self.params.backoff_ticks:
            self.backoff_until = obs.tick + self.params.backoff_ticks
            self.turn = float(self.rng.uniform(-1.0, 1.0))
        if obs.tick < self.backoff_until:   # direct control; clear_goal drops the goal, re-sent afterwards
            self.target = None
            return Action(velocity=(-0.2, self.turn), clear_goal=True)
        if self.target is not None and obs.nav.state in ("reached", "unreachable", "blocked"):
            # the navigator could not get there, or got there and what is still unseen is hidden from it
            self.excluded[self.target] = obs.tick + self.params.exclude_ticks
            self.target = None
        if self.target is None or obs.nav.state == "idle" or not self._worth_it(obs.known):
            return self._choose(obs)
        return Action()   # neither goal nor velocity: the navigator keeps driving to the current goal

    def _worth_it(self, known: np.ndarray) -> bool:
        assert self.target is not None
        r, c = self.target
        return bool((known[max(r - LOOK_CELLS, 0):r + LOOK_CELLS + 1,
                           max(c - LOOK_CELLS, 0):c + LOOK_CELLS + 1] == UNSEEN).any())

    def _choose(self, obs: Observation) -> Action:
        self.excluded = {cell: until for cell, until in self.excluded.items() if until > obs.tick}
        exclude = np.zeros(obs.known.shape, dtype=bool)   # a new array: obs.known itself is never written
        for cell in self.excluded:
            exclude[cell] = True
        if self.claims:
            rows, cols = np.indices(obs.known.shape)
            x_m, y_m = (cols + 0.5) * CELL_M, (rows + 0.5) * CELL_M   # cell centres; row 0 is at the bottom
            for x, y in self.claims.values():
                exclude |= (x_m - x) ** 2 + (y_m - y) ** 2 <= self.params.claim_radius_m ** 2
        here = cell_of(obs.pose.x, obs.pose.y)
        found = grid.nearest_reachable_unseen(obs.known, here, self.robot.radius, exclude=exclude)
        if found is None and self.claims:   # only claimed space is left: go there anyway
            found = grid.nearest_reachable_unseen(obs.known, here, self.robot.radius)
        if found is None:                   # nothing left in reach: stop and forget the goal
            self.target = None
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        previous, self.target = self.target, (int(found[0][0]), int(found[0][1]))
        x, y = cell_centre(*self.target)
        if self.target == previous:
            return Action(goal=(x, y))
        return Action(goal=(x, y), messages=(Claim(sender=self.robot.id, x=x, y=y),))
