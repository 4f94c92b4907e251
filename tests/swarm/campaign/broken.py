"""An algorithm that crashes, for the 'a broken run does not stop the campaign' test."""

from dataclasses import dataclass

from swarm.base.params import check_int


@dataclass(frozen=True)
class BoomParams:
    at_tick: int = 3

    def __post_init__(self) -> None:
        check_int("at_tick", self.at_tick, 0)


class Boom:
    name = "boom"
    Params = BoomParams

    def reset(self, robot, params, rng):
        self.at = params.at_tick

    def act(self, obs):
        if obs.tick >= self.at:
            raise RuntimeError(f"boom at tick {obs.tick}")
        from swarm.api import Action

        return Action(velocity=(0.0, 0.5))
