"""Build the self-contained replay page: the template with the CSS, the script and the recording inlined.

The page embeds the ``.swr`` bytes unchanged (base64, 4/3 of the file) rather than a JSON rendering of them:
one format, one decoder per language, and the page is little larger than the recording. The script decodes it
with the browser's own ``DecompressionStream``, so the page needs no server and no network.

A large recording is embedded in pieces of at most ``PIECE_BYTES`` (a browser's strings stop at 512 MiB,
and a swarm-size recording can be larger); each piece is its own ``<script class="swr-data">`` element.
"""

from __future__ import annotations

import base64
import html
import json
import re
from importlib import resources
from pathlib import Path
from typing import Any

from maps.io import atomic_write_bytes

from swarm.record import Recording
from swarm.draw import ROBOT_COLOURS, SEEN_FREE, UNSEEN_FREE, UNSEEN_WALL_FADE
from swarm.record.container import bad
from swarm.record.reader import read_bytes

OTHERS_FREE = (226, 229, 236)
"""In a robot's view: free cells some other robot has seen but this one has not."""
PIECE_BYTES = 36 * 1024 * 1024
"""Recording bytes per embedded base64 piece (48 MiB of text); a multiple of 3, so each piece decodes alone."""
_PLACEHOLDER = re.compile(r"\{\{(TITLE|STYLE|SCRIPT|CONFIG|DATA)\}\}")


def _asset(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def title_of(rec: Recording) -> str:
    """A one-line description of the recorded run, e.g. ``frontier x4 on building 50, seed 1``.

    The reader checks only that HEAD ``spec`` is a map; a crafted file may hold anything inside it, so a
    section that is not a map is the one-line error for a bad recording, not an AttributeError."""
    spec = rec.spec
    for section in ("algorithm", "map"):
        if not isinstance(spec.get(section, {}), dict):
            raise bad(rec.path, f"HEAD spec field {section!r} is not a map")
    algorithm = spec.get("algorithm", {}).get("name", "?")
    m = spec.get("map", {})
    where = m.get("path") if m.get("kind") == "file" else f"{m.get('kind', '?')} {m.get('size', '?')}"
    return f"{algorithm} x{rec.n_robots} on {where}, seed {spec.get('seed', '?')}"


def build_html(data: bytes, source: str = "<bytes>") -> str:
    """The viewer page for recording ``data`` (validated first: a corrupt file raises InvalidInput)."""
    rec = Recording(data, source)
    config: dict[str, Any] = {"robotColours": [list(c) for c in ROBOT_COLOURS], "unseenFree": list(UNSEEN_FREE),
                              "seenFree": list(SEEN_FREE), "othersFree": list(OTHERS_FREE),
                              "unseenWallFade": UNSEEN_WALL_FADE,
                              "source": Path(source).name}
    parts = {
        "TITLE": html.escape(title_of(rec)),
        "STYLE": _asset("viewer.css"),
        "SCRIPT": _asset("viewer.js"),
        # "</" cannot end the <script> element early once escaped; JSON allows "\/".
        "CONFIG": json.dumps(config).replace("</", "<\\/"),
        "DATA": "\n".join(f'<script type="application/octet-stream" class="swr-data">'
                           f'{base64.b64encode(data[at:at + PIECE_BYTES]).decode("ascii")}</script>'
                           for at in range(0, max(len(data), 1), PIECE_BYTES)),
    }
    return _PLACEHOLDER.sub(lambda m: parts[m.group(1)], _asset("template.html"))


def write_html(recording: str | Path, out: str | Path) -> Path:
    """Read and validate ``recording``, write its viewer page to ``out`` atomically."""
    return atomic_write_bytes(Path(out), build_html(read_bytes(recording), str(recording)).encode("utf-8"))
