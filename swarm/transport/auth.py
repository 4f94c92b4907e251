"""Who may take part in a run over the network: per-run secrets, per-robot tokens, signed act packets.

A run that listens for remote agents has a **run secret** (32 random bytes). Everything an agent needs is
derived from it per robot, so an agent can be given the power to act for its own robot and no other:

* the **robot key** ``HMAC-SHA256(secret, "swarm robot key" | run id | robot)``, which a **robot token**
  (``swarm-robot-token:<run>:<robot>:<hex>``) carries;
* from the robot key, the robot's zenoh **user/password** (``robot-<id>``; zenoh's usrpwd authentication
  is a challenge-response, the password never travels) and, with the **run nonce** (16 random bytes the
  runtime draws at start and sends each agent as its ``reset`` packet's attachment), its **act key**;
* every act packet carries, as its zenoh attachment, the tick (uint64, little-endian) and
  ``HMAC-SHA256(act key, "swarm act" | run id | robot | tick | payload)`` (:func:`sign_act`). The nonce
  makes acts captured in one run worthless in the next, even with the same run id and secret.

The runtime writes a zenoh access-control policy (:func:`access_control`) that lets robot N's user
subscribe only to robot N's ``obs``/``reset`` keys and the run's ``end`` key, put only on robot N's ``act``
key and declare only robot N's liveliness token: everything else is denied. docs/wire-format.md says what
an attacker can and cannot do.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import re
import secrets
import struct
import tempfile
from dataclasses import dataclass
from pathlib import Path

from swarm.base.errors import InvalidInput

SECRET_BYTES = 32
RUN_SECRET_PREFIX = "swarm-run-secret:"
ROBOT_TOKEN_PREFIX = "swarm-robot-token:"
TOKEN_ENV = "SWARM_TOKEN"
TAG_BYTES = 32
NONCE_BYTES = 16  # the run nonce: the attachment of every reset packet
ATTACHMENT = struct.Struct("<Q32s")  # tick, HMAC tag: the attachment of every signed act packet
RUN_ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")
RUN_ID_ALLOWED = ("1-100 characters of letters, digits, '_', '.' and '-', starting with a letter or digit "
                  "(no zenoh key-expression syntax: * $ ? # / or spaces)")


def check_run_id(run_id: object, field: str = "--run-id") -> str:
    """A run id that is one plain zenoh key chunk: no wildcards, no ``/``, no ``$*``, no spaces."""
    if not isinstance(run_id, str) or not RUN_ID_PATTERN.fullmatch(run_id):
        raise InvalidInput(field, run_id, RUN_ID_ALLOWED)
    return run_id


def _mac(key: bytes, *parts: bytes) -> bytes:
    return hmac.new(key, b"\0".join(parts), hashlib.sha256).digest()


@dataclass(frozen=True)
class RobotToken:
    """What one robot's agent holds: the power to join run ``run_id`` as robot ``robot`` and act for it
    (``nonce``: the run nonce its act key is bound to, :meth:`for_run`; empty until the reset says it)."""

    run_id: str
    robot: int
    key: bytes
    nonce: bytes = b""

    def for_run(self, nonce: bytes) -> RobotToken:
        """This token bound to one start of the run: its act key depends on the run nonce."""
        return RobotToken(self.run_id, self.robot, self.key, bytes(nonce))

    @property
    def user(self) -> str:
        """The zenoh usrpwd user name."""
        return f"robot-{self.robot}"

    @property
    def password(self) -> str:
        """The zenoh usrpwd password (hex; zenoh proves it with a challenge, it is never sent)."""
        return _mac(self.key, b"swarm zenoh usrpwd").hex()

    @property
    def act_key(self) -> bytes:
        """The key act packets are signed with: the robot key's, bound to the run nonce."""
        return _mac(self.key, b"swarm act key", self.nonce)

    def text(self) -> str:
        return f"{ROBOT_TOKEN_PREFIX}{self.run_id}:{self.robot}:{self.key.hex()}"


@dataclass(frozen=True)
class RunSecret:
    """The secret of one or more runs; robot tokens are derived from it and the run id."""

    key: bytes

    @classmethod
    def generate(cls) -> "RunSecret":
        return cls(secrets.token_bytes(SECRET_BYTES))

    def robot_token(self, run_id: str, robot: int) -> RobotToken:
        return RobotToken(run_id, robot, _mac(self.key, b"swarm robot key", run_id.encode(), str(robot).encode()))

    def text(self) -> str:
        return f"{RUN_SECRET_PREFIX}{self.key.hex()}"


def parse_token(text: str, field: str) -> RunSecret | RobotToken:
    """A run secret or a robot token from its text form (surrounding whitespace ignored)."""
    allowed = (f"'{RUN_SECRET_PREFIX}<64 hex digits>' or '{ROBOT_TOKEN_PREFIX}<run>:<robot>:<64 hex digits>' "
               "(as swarm run writes them)")
    text = text.strip()
    try:
        if text.startswith(RUN_SECRET_PREFIX):
            key = bytes.fromhex(text[len(RUN_SECRET_PREFIX):])
            if len(key) == SECRET_BYTES:
                return RunSecret(key)
        elif text.startswith(ROBOT_TOKEN_PREFIX):
            run_id, robot, key_hex = text[len(ROBOT_TOKEN_PREFIX):].rsplit(":", 2)
            key = bytes.fromhex(key_hex)
            if len(key) == SECRET_BYTES and RUN_ID_PATTERN.fullmatch(run_id) and robot.isdigit():
                return RobotToken(run_id, int(robot), key)
    except ValueError:
        pass
    raise InvalidInput(field, "<hidden>" if len(text) >= 40 else text, allowed)


def read_token_file(path: Path, field: str = "--token-file") -> RunSecret | RobotToken:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise InvalidInput(field, str(path), f"a readable token file ({reason})") from None
    return parse_token(text, f"{field} {path}")


def create_secret_file(path: Path) -> RunSecret:
    """Write a fresh run secret to ``path``, readable by its owner only; refuses to overwrite a file."""
    secret = RunSecret.generate()
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return _expect_secret(read_token_file(path), path)
    except OSError as exc:
        raise InvalidInput("--token-file", str(path), f"a path where a token file can be created ({exc.strerror})") from None
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(secret.text() + "\n")
    return secret


def _expect_secret(token: RunSecret | RobotToken, path: Path) -> RunSecret:
    if not isinstance(token, RunSecret):
        raise InvalidInput("--token-file", str(path), "a run secret for the runtime (this file holds one robot's token)")
    return token


def runtime_secret(token_file: Path | None) -> RunSecret:
    """The runtime's secret: ``token_file`` (read, or created if missing), else ``$SWARM_TOKEN``, else new."""
    if token_file is not None:
        return create_secret_file(token_file) if not token_file.exists() else _expect_secret(read_token_file(token_file), token_file)
    env = os.environ.get(TOKEN_ENV)
    if env:
        token = parse_token(env, TOKEN_ENV)
        if not isinstance(token, RunSecret):
            raise InvalidInput(TOKEN_ENV, "<robot token>", "a run secret for the runtime, not one robot's token")
        return token
    return RunSecret.generate()


def agent_token(token: RunSecret | RobotToken, run_id: str, robot: int, field: str) -> RobotToken:
    """The robot token an agent uses: derived from a run secret, or a robot token checked to be for this
    run and robot."""
    if isinstance(token, RunSecret):
        return token.robot_token(run_id, robot)
    if token.run_id != run_id or token.robot != robot:
        raise InvalidInput(field, f"token for run {token.run_id} robot {token.robot}",
                           f"the token of run {run_id} robot {robot}")
    return token


# ------------------------------------------------------------------------------ signed act packets ----
def new_nonce() -> bytes:
    """A fresh run nonce: a runtime draws one each time it starts."""
    return secrets.token_bytes(NONCE_BYTES)


def sign_act(token: RobotToken, tick: int, payload: bytes, act_key: bytes | None = None) -> bytes:
    """The attachment of an act packet for ``tick``: the tick and its HMAC tag (``act_key``: the token's,
    computed once by a caller that signs every tick)."""
    key = act_key if act_key is not None else token.act_key
    return ATTACHMENT.pack(tick, _mac(key, b"swarm act", token.run_id.encode(), str(token.robot).encode(),
                                      str(tick).encode(), payload))


def verify_act(token: RobotToken, act_key: bytes, attachment: bytes | None, payload: bytes) -> int | None:
    """The tick an act packet's attachment vouches for, or None if it is missing or its tag is wrong."""
    if attachment is None or len(attachment) != ATTACHMENT.size:
        return None
    tick, tag = ATTACHMENT.unpack(attachment)
    good = sign_act(token, tick, payload, act_key)[8:]
    return tick if hmac.compare_digest(tag, good) else None


# --------------------------------------------------------------------------------- zenoh config ----
class Credentials:
    """The runtime's zenoh usrpwd dictionary of the remote robots' users, in a private temporary folder
    (zenoh reads it from a file); :meth:`remove` deletes it."""

    def __init__(self, tokens: list[RobotToken]) -> None:
        self._folder = Path(tempfile.mkdtemp(prefix="swarm-auth-"))  # mode 0700
        self.path = self._folder / "users.txt"
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            for t in tokens:
                f.write(f"{t.user}:{t.password}\n")
            if not tokens:  # zenoh needs a dictionary; this one admits nobody
                f.write(f"nobody:{secrets.token_hex(32)}\n")

    def remove(self) -> None:
        for p in (self.path, self._folder):
            try:
                p.unlink() if p.is_file() else p.rmdir()
            except OSError:
                pass


def access_control(prefix: str, robots: list[int]) -> dict:
    """zenoh's access-control policy for a run: robot N's user may subscribe to its own robot's keys
    (``.../robot/N/**``: ``obs`` and ``reset``) and the run's ``end``, put only on its own ``act`` key,
    declare only its own liveliness token, and see the runtime's declarations and data for those keys;
    nothing else (the default is deny)."""
    rules, subjects, policies = [], [], []
    for n in robots:
        own = f"{prefix}/robot/{n}"
        rules += [
            {"id": f"sub-{n}", "flows": ["ingress"], "permission": "allow", "messages": ["declare_subscriber"],
             "key_exprs": [f"{own}/**", f"{prefix}/end"]},
            {"id": f"put-{n}", "flows": ["ingress"], "permission": "allow", "messages": ["put"],
             "key_exprs": [f"{own}/act"]},
            {"id": f"alive-{n}", "flows": ["ingress"], "permission": "allow", "messages": ["liveliness_token"],
             "key_exprs": [f"{own}/alive"]},
            {"id": f"out-{n}", "flows": ["egress"], "permission": "allow",
             "messages": ["put", "declare_subscriber", "liveliness_token"], "key_exprs": [f"{own}/**", f"{prefix}/end"]},
            {"id": f"watch-{n}", "flows": ["egress"], "permission": "allow",
             "messages": ["declare_liveliness_subscriber"], "key_exprs": [f"{prefix}/robot/*/alive"]},
        ]
        subjects.append({"id": f"robot-{n}", "usernames": [f"robot-{n}"]})
        policies.append({"rules": [f"sub-{n}", f"put-{n}", f"alive-{n}", f"out-{n}", f"watch-{n}"],
                         "subjects": [f"robot-{n}"]})
    return {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects,
            "policies": policies}
