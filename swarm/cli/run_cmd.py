"""``swarm run`` (one simulation) and ``swarm algorithms`` (what can run)."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click

from swarm.base.errors import InvalidInput

from swarm.sim.spec import MAX_ROBOTS
from swarm.sim.spec_input import check_size_flag, flag_overrides, load_spec_file, merge
from .group import cli
from .checks import FiniteSeconds, check_output_path, writing
from .export_cmd import MAP_EVERY_HELP
from .options import parse_params


def build_spec_mapping(spec_file: Path | None, flags: dict[str, Any], sets: tuple[str, ...],
                       algorithm_params: tuple[str, ...], map_params: tuple[str, ...]) -> dict[str, Any]:
    """The run spec as a mapping: the ``--spec`` file, then flags that were given, then ``--set``
    (:mod:`swarm.sim.spec_input` reads the file and the flags as :func:`swarm.run` reads its arguments)."""
    data: dict[str, Any] = load_spec_file(spec_file) if spec_file else {}
    over = flag_overrides(flags, "--")
    if algorithm_params:
        over.setdefault("algorithm", {})["params"] = parse_params(algorithm_params)
    if map_params:
        over.setdefault("map", {})["params"] = parse_params(map_params, "--map-param")
    data = merge(data, over)
    if sets:
        data = merge(data, parse_params(sets, "--set"))
    check_size_flag(data, flags, "--")
    return data


@cli.command("run")
@click.option("--spec", "spec_file", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="A run spec TOML; flags below override it.")
@click.option("--map", "map_", default=None, metavar="building|cave|FILE",
              help="Generated map kind, or a map file (.npz, .pgm, .csv, ROS .yaml). [default: building]")
@click.option("--size", default=None, metavar="N|WxH", help="Map size in tiles (1 m). [default: 50]")
@click.option("--map-seed", type=click.IntRange(0, 2**63 - 1), default=None, help="Map seed (default: from --seed).")
@click.option("--map-param", "map_params", multiple=True, metavar="KEY=VALUE", help="Generator parameter.")
@click.option("--robots", type=click.IntRange(1, MAX_ROBOTS), default=None, help="Number of robots. [default: 4]")
@click.option("--spawn", type=click.Choice(["together", "random"]), default=None, help="[default: together]")
@click.option("--algorithm", default=None, help="Algorithm name (see 'swarm algorithms') or module:Class.")
@click.option("--param", "algorithm_params", multiple=True, metavar="KEY=VALUE", help="Algorithm parameter.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=None, help="Master seed. [default: 0]")
@click.option("--max-ticks", type=click.IntRange(1), default=None, help="Tick limit. [default: 36000]")
@click.option("--explored", type=click.FloatRange(0, 1, min_open=True), default=None,
              help="Stop at this explored fraction. [default: 0.99]")
@click.option("--transport", type=click.Choice(["inprocess", "zenoh"]), default=None)
@click.option("--set", "sets", multiple=True, metavar="SECTION.KEY=VALUE",
              help="Any spec value, e.g. --set lidar.range_m=10 --set motion.max_speed=3.")
@click.option("--listen", multiple=True, metavar="ENDPOINT",
              help="zenoh endpoint remote agents connect to, e.g. tcp/127.0.0.1:7447 (needs --transport zenoh).")
@click.option("--remote", multiple=True, type=click.IntRange(0), metavar="ID",
              help="Robot ids whose agents run in other processes ('swarm agent'); repeatable.")
@click.option("--agent-timeout", type=FiniteSeconds(), default=10.0, show_default=True,
              help="Seconds to wait for a remote agent's action before its robot is marked failed.")
@click.option("--run-id", default=None, help="Name of the run on the wire (default: the spec key + a nonce).")
@click.option("--token-file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="The run secret remote agents authenticate with: read, or created (mode 0600) if missing. "
                   "Default: $SWARM_TOKEN, else a new secret whose robot tokens are printed.")
@click.option("--ros2", "ros2", is_flag=True,
              help="Speak ROS 2 live as rmw_zenoh does: /clock, the robots' poses, scans, maps, /tf, goals and "
                   "radio markers every tick (needs the ros extra; docs/ros2.md).")
@click.option("--ros-domain", type=click.IntRange(0, 232), default=None, help="ROS_DOMAIN_ID. [default: 0]")
@click.option("--ros-distro", type=click.Choice(["humble", "jazzy", "kilted", "rolling"]), default=None,
              help="The ROS 2 distribution of the peers (Humble has no type hashes). [default: jazzy]")
@click.option("--ros-connect", multiple=True, metavar="ENDPOINT",
              help="An rmw_zenohd router to publish through (watching only). [default: tcp/127.0.0.1:7447]")
@click.option("--ros-listen", multiple=True, metavar="ENDPOINT",
              help="Listen for ROS 2 nodes that log in with the printed zenoh configs (needed by --ros-external).")
@click.option("--ros-external", multiple=True, type=click.IntRange(0), metavar="ID",
              help="Robot ids driven from ROS 2 (/robot_ID/goal_pose, /robot_ID/cmd_vel), in lockstep; repeatable.")
@click.option("--ros-timeout", type=FiniteSeconds(), default=10.0, show_default=True,
              help="Seconds a tick waits for an external robot's command before it keeps its last one.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False, path_type=Path), help="Write the result JSON.")
@click.option("--gif", type=click.Path(dir_okay=False, path_type=Path), help="Write an animation.")
@click.option("--mp4", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the animation as MP4 (needs the 'video' extra: imageio-ffmpeg).")
@click.option("--record", "record_out", type=click.Path(dir_okay=False, path_type=Path),
              help="Record the run (.swr) for 'swarm view'.")
@click.option("--mcap", "mcap_out", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the run as MCAP with ROS 2 messages, for Foxglove and 'ros2 bag play' (needs the 'ros' "
                   "extra; docs/ros2.md).")
@click.option("--mcap-map-every", type=click.IntRange(1, 1_000_000), default=None,
              help=f"With --mcap or --ros2: the {MAP_EVERY_HELP}. [default: 10]")
@click.option("--print-spec", is_flag=True,
              help="Print the fully-resolved spec as a TOML run spec (every default filled in) and exit; "
                   "--spec reads it back to the same run.")
def run_cmd(spec_file: Path | None, map_: str | None, size: str | None, map_seed: int | None,
            map_params: tuple[str, ...], robots: int | None, spawn: str | None, algorithm: str | None,
            algorithm_params: tuple[str, ...], seed: int | None, max_ticks: int | None, explored: float | None,
            transport: str | None, sets: tuple[str, ...], listen: tuple[str, ...], remote: tuple[int, ...],
            agent_timeout: float, run_id: str | None, token_file: Path | None, ros2: bool, ros_domain: int | None,
            ros_distro: str | None, ros_connect: tuple[str, ...], ros_listen: tuple[str, ...],
            ros_external: tuple[int, ...], ros_timeout: float, json_out: Path | None, gif: Path | None,
            mp4: Path | None, record_out: Path | None, mcap_out: Path | None, mcap_map_every: int | None,
            print_spec: bool) -> None:
    """Run one exploration and print a one-line summary.

    With no arguments: 4 robots with the frontier explorer on a 50 x 50 building, seed 0. On a terminal,
    stderr shows the run's progress (tick, explored share, speed, and numba compiling on a first run).
    """

    from swarm.sim.loop import Simulation
    from swarm.sim.spec import RunSpec
    from .run_progress import RunProgress

    flags = {"map": map_, "size": size, "map_seed": map_seed, "robots": robots, "spawn": spawn,
             "algorithm": algorithm, "seed": seed, "max_ticks": max_ticks, "explored": explored,
             "transport": transport}
    spec = RunSpec.from_mapping(build_spec_mapping(spec_file, flags, sets, algorithm_params, map_params))
    ros = RosFlags(ros2, ros_domain, ros_distro, ros_connect, ros_listen, ros_external, ros_timeout)
    _check_transport_flags(spec, listen, remote, run_id, token_file, ros)
    if print_spec:
        click.echo(spec.to_toml(), nl=False)
        return
    if mp4 is not None:
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise InvalidInput("--mp4", str(mp4), "an MP4 path once the video extra is installed "
                               "(pip install 'swarm-sim[video]')") from None
    if mcap_map_every is not None and mcap_out is None and not ros2:
        raise InvalidInput("--mcap-map-every", mcap_map_every, "only with --mcap or --ros2")
    if mcap_out is not None:
        from swarm.ros2 import require_extra

        require_extra("--mcap", str(mcap_out), "an MCAP path")
    for flag, path in (("--json", json_out), ("--gif", gif), ("--mp4", mp4), ("--record", record_out),
                       ("--mcap", mcap_out)):
        if path is not None:
            check_output_path(flag, path)
    live_topics = None
    if ros.on:
        from swarm.ros2.external import LiveTopics

        live_topics = LiveTopics(mcap_map_every or 10)
    options = _transport_options(spec, listen, remote, agent_timeout, run_id, token_file, ros, live_topics)
    with RunProgress(spec.stop.max_ticks, spec.stop.explored) as progress:
        sim = Simulation(spec, transport=options)
        if live_topics is not None:
            live_topics.attach(sim)
        recorder = None
        if gif is not None or mp4 is not None:
            from swarm.record.animation import GifRecorder

            recorder = GifRecorder(sim.truth)
            sim.observers = (recorder,)
        if progress.enabled:
            sim.observers = (*sim.observers, progress)
        run_recorder = None
        if record_out is not None:
            from swarm.record import Recorder

            run_recorder = Recorder.attach(sim)
        mcap_recorder = None
        if mcap_out is not None:
            from swarm.ros2.mcap_export import McapRecorder

            mcap_recorder = McapRecorder.attach(sim, mcap_map_every or 10)
        result = sim.run()
    click.echo(result.one_line())
    outputs = (("--json", json_out, lambda p: result.write_json(p)),
               ("--gif", gif if recorder is not None else None, lambda p: recorder.save(p)),
               ("--mp4", mp4 if recorder is not None else None, lambda p: recorder.save_mp4(p)),
               ("--record", record_out if run_recorder is not None else None,
                lambda p: (run_recorder.finish(sim, result), run_recorder.save(p))[1]),
               ("--mcap", mcap_out if mcap_recorder is not None else None, lambda p: mcap_recorder.save(sim, p)))
    for flag, path, write in outputs:
        if path is None:
            continue
        with writing(flag, path):  # checked before the run; a disk may still fill up
            click.echo(f"wrote {write(path)}")


@dataclass(frozen=True)
class RosFlags:
    """The ``--ros*`` flags of ``swarm run`` (None: not given)."""

    on: bool = False
    domain: int | None = None
    distro: str | None = None
    connect: tuple[str, ...] = ()
    listen: tuple[str, ...] = ()
    external: tuple[int, ...] = ()
    timeout: float = 10.0

    def check(self, spec, remote: tuple[int, ...]) -> None:
        """Well formed, given with ``--ros2``, and fitting the spec and the remote agents."""
        from swarm.transport.sessions import check_endpoint

        given = {"--ros-domain": self.domain, "--ros-distro": self.distro, "--ros-connect": list(self.connect),
                 "--ros-listen": list(self.listen), "--ros-external": list(self.external)}
        if not self.on:
            for flag, value in given.items():
                if value:
                    raise InvalidInput(flag, value, "only with --ros2")
            return
        for flag, endpoints in (("--ros-connect", self.connect), ("--ros-listen", self.listen)):
            for endpoint in endpoints:
                check_endpoint(endpoint, flag)
        for endpoint in self.listen:
            if not endpoint.startswith("unixsock-stream/") and endpoint.rsplit(":", 1)[1] == "0":
                raise InvalidInput("--ros-listen", endpoint, "a fixed port (the zenoh configs printed for the "
                                   "ROS 2 nodes name it), e.g. tcp/127.0.0.1:7448")
        if self.connect and self.listen:
            raise InvalidInput("--ros-connect", list(self.connect), "either --ros-connect (a router, watching only) "
                               "or --ros-listen (ROS 2 nodes log in), not both")
        for r in self.external:
            if r >= spec.robots.count:
                raise InvalidInput("--ros-external", r, f"a robot id below --robots ({spec.robots.count})")
            if r in remote:
                raise InvalidInput("--ros-external", r, "a robot not also driven by a remote agent (--remote)")
        if self.external and not self.listen:
            raise InvalidInput("--ros-listen", None, "an endpoint the ROS 2 drivers of --ros-external log in to, "
                               "e.g. tcp/127.0.0.1:7448 (commands through a router could come from anyone)")
        try:
            import rosbags  # noqa: F401
        except ImportError:
            raise InvalidInput("--ros2", True, "ROS 2 once the ros extra is installed (pip install 'swarm-sim[ros]')") \
                from None


def _check_transport_flags(spec, listen: tuple[str, ...], remote: tuple[int, ...], run_id: str | None,
                           token_file: Path | None, ros: RosFlags = RosFlags()) -> None:
    """The transport flags are well formed and fit the spec (nothing opened or written yet)."""
    from swarm.transport.auth import check_run_id
    from swarm.transport.sessions import check_endpoint

    ros.check(spec, remote)

    for endpoint in listen:
        check_endpoint(endpoint, "--listen")
    if run_id is not None:
        check_run_id(run_id)
    if (listen or remote) and spec.transport != "zenoh":
        raise InvalidInput("--remote" if remote else "--listen", list(remote or listen),
                           "remote agents only with --transport zenoh")
    for r in remote:
        if r >= spec.robots.count:
            raise InvalidInput("--remote", r, f"a robot id below --robots ({spec.robots.count})")
    if remote and not listen:
        raise InvalidInput("--listen", None, "an endpoint remote agents can connect to, e.g. tcp/127.0.0.1:7447")
    if token_file is not None and not (listen or ros.listen):
        raise InvalidInput("--token-file", str(token_file), "only with --listen (remote agents) or --ros-listen")


def _transport_options(spec, listen: tuple[str, ...], remote: tuple[int, ...], timeout: float,
                       run_id: str | None, token_file: Path | None, ros: RosFlags = RosFlags(),
                       live_topics=None):
    """How the run reaches its remote agents: their secret (read or created) and the commands to start them,
    printed once the runtime listens (a --listen endpoint that cannot be bound fails first, with no command
    to start an agent for); and, with --ros2, the ROS 2 node around the run's host (:func:`_ros_wrap`)."""
    from swarm.sim.loop import TransportOptions
    from swarm.transport.auth import TOKEN_ENV, runtime_secret
    from swarm.transport.zenoh_host import new_run_id

    secret = runtime_secret(token_file) if listen or ros.listen else None
    if remote or ros.listen:
        run_id = run_id or new_run_id(spec.key)
    lines: list[str] = []
    if remote:
        assert secret is not None and run_id is not None
        for r in remote:
            if token_file is not None:
                how = f"--token-file {token_file}"
            elif os.environ.get(TOKEN_ENV):
                how = f"(with ${TOKEN_ENV} set)"
            else:
                how = f"--token {secret.robot_token(run_id, r).text()}"
            lines.append(f"waiting for: swarm agent --connect {listen[0]} --run {run_id} --robot {r} {how}")

    def announce() -> None:
        for line in lines:
            click.echo(line, err=True)

    return TransportOptions(listen=listen, remote=remote, timeout_s=timeout, run_id=run_id, secret=secret,
                            on_listening=announce if lines else None,
                            wrap=_ros_wrap(ros, secret, run_id, live_topics) if ros.on else None)


def _ros_wrap(ros: RosFlags, secret, run_id: str | None, live_topics=None):
    """The run's host wrapped in a :class:`~swarm.ros2.external.RosHost` on a new ROS 2 node; once its session
    is open, stderr says where it publishes and, when it listens, which zenoh session config each ROS 2 node
    uses to watch (``viewer``) or to drive an external robot (``robot-N``)."""
    def wrap(host):
        from swarm.ros2.external import RosHost
        from swarm.ros2.live import open_node

        domain, distro = ros.domain or 0, ros.distro or "jazzy"
        node, access = open_node(connect=ros.connect or (() if ros.listen else ("tcp/127.0.0.1:7447",)),
                                 listen=ros.listen, domain=domain, distro=distro, secret=secret,
                                 run_id=run_id or "swarm", external=ros.external)
        if access is None:
            where = ", ".join(ros.connect) or "the rmw_zenohd router at tcp/127.0.0.1:7447"
            click.echo(f"ROS 2 ({distro}, domain {domain}): publishing through {where}", err=True)
        else:
            click.echo(f"ROS 2 ({distro}, domain {domain}): listening on {', '.join(ros.listen)}; watch with "
                       f"ZENOH_SESSION_CONFIG_URI={access.configs['viewer']}", err=True)
            for robot in ros.external:
                click.echo(f"waiting for: a ROS 2 node driving robot {robot} (/robot_{robot}/goal_pose or cmd_vel) "
                           f"with ZENOH_SESSION_CONFIG_URI={access.configs[f'robot-{robot}']}", err=True)
        if live_topics is not None:
            live_topics.use(node)
        return RosHost(host, node, external=ros.external, timeout_s=ros.timeout)
    return wrap


@cli.command("agent")
@click.option("--connect", required=True, metavar="ENDPOINT", help="The runtime's --listen endpoint.")
@click.option("--run", "run_id", required=True, help="The run id the runtime printed.")
@click.option("--robot", type=click.IntRange(0, 999), required=True, help="Which robot this agent drives.")
@click.option("--algorithm", default=None, help="Algorithm to run (default: the run spec's).")
@click.option("--timeout", type=FiniteSeconds(), default=60.0, show_default=True,
              help="Give up after this many seconds without hearing from the runtime.")
@click.option("--token", default=None, metavar="TOKEN",
              help="This robot's token as 'swarm run' printed it (visible to other users in 'ps': prefer "
                   "--token-file or $SWARM_TOKEN).")
@click.option("--token-file", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="A file holding the run secret or this robot's token (waited for until --timeout).")
def agent_cmd(connect: str, run_id: str, robot: int, algorithm: str | None, timeout: float, token: str | None,
              token_file: Path | None) -> None:
    """Run one robot's algorithm in this process against 'swarm run --transport zenoh --listen ... --remote ID'."""
    from swarm.transport.auth import TOKEN_ENV, agent_token, check_run_id, parse_token, read_token_file
    from swarm.transport.remote import run_agent
    from swarm.transport.sessions import check_endpoint

    check_endpoint(connect, "--connect")
    check_run_id(run_id, "--run")
    if token is not None and token_file is not None:
        raise InvalidInput("--token", "<hidden>", "either --token or --token-file, not both")
    if algorithm is not None:
        from swarm.plugins import explorers as registry

        registry.load(algorithm)
    if token is not None:
        held, field = parse_token(token, "--token"), "--token"
    elif token_file is not None:
        deadline = time.monotonic() + timeout
        while not token_file.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        held, field = read_token_file(token_file), "--token-file"
    elif os.environ.get(TOKEN_ENV):
        held, field = parse_token(os.environ[TOKEN_ENV], TOKEN_ENV), TOKEN_ENV
    else:
        raise InvalidInput("--token", None, f"this robot's token (--token, --token-file or ${TOKEN_ENV}), "
                           "as 'swarm run' printed it")
    code = run_agent(connect, run_id, robot, agent_token(held, run_id, robot, field), algorithm=algorithm,
                     timeout_s=timeout, log=lambda text: click.echo(text, err=True))
    if code:
        raise click.exceptions.Exit(code)


@cli.group("algorithms", invoke_without_command=True)
@click.pass_context
def algorithms_cmd(ctx: click.Context) -> None:
    """List the installed exploration algorithms and their parameters ('swarm algorithms check NAME'
    checks one against the plugin contract)."""
    if ctx.invoked_subcommand is not None:
        return
    from swarm.plugins import explorers as registry

    for name, target in registry.available().items():
        click.echo(f"{name}  ({target})")
        try:
            rows = registry.describe(name)
        except InvalidInput as exc:
            click.echo(f"    cannot load: {exc}")
            continue
        for param, default, typ in rows:
            click.echo(f"    {param} = {default!r}  [{typ}]")


_CHECK_NAMES = ("contract", "params", "actions", "determinism", "messages", "observation", "robustness",
                "transports")  # swarm.testing.CHECKS, named here so that --help needs no import


@algorithms_cmd.command("check")
@click.argument("name")
@click.option("--param", "algorithm_params", multiple=True, metavar="KEY=VALUE", help="Algorithm parameter.")
@click.option("--map", "map_kind", type=click.Choice(["building", "cave"]), default="building", show_default=True)
@click.option("--size", type=click.IntRange(1, 10_000), default=20, show_default=True, help="Map size in tiles (1 m).")
@click.option("--robots", type=click.IntRange(1, MAX_ROBOTS), default=2, show_default=True)
@click.option("--ticks", type=click.IntRange(1, 1_000_000), default=60, show_default=True,
              help="Length of the check's runs.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True)
@click.option("--check", "only", multiple=True, type=click.Choice(_CHECK_NAMES),
              help="Run only this check (repeatable; default: all).")
def algorithms_check_cmd(name: str, algorithm_params: tuple[str, ...], map_kind: str, size: int, robots: int,
                         ticks: int, seed: int, only: tuple[str, ...]) -> None:
    """Check algorithm NAME (registered, or package.module:Class) against the plugin contract: print each
    check passed and exit 0, or the one failure and exit 1 (docs/plugins.md lists the checks)."""
    from swarm.testing import ExplorerCheckError, check_explorer
    from .compile_notice import compile_notice

    params = parse_params(algorithm_params) if algorithm_params else None
    try:
        with compile_notice():
            report = check_explorer(name, map_kind=map_kind, size=size, robots=robots, ticks=ticks, seed=seed,
                                    params=params, checks=only or None, progress=lambda r: click.echo(str(r)))
    except ExplorerCheckError as exc:
        click.echo(f"FAIL {exc}", err=True)
        raise click.exceptions.Exit(1) from None
    click.echo(f"{name}: {len(report.results)} checks passed ({report.seconds:.1f} s)")
