"""README examples stay true: every TOML block parses and validates against the code it documents."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from maps.io import check_legend
from radio import config_from_mapping
from swarm.campaign import parse_campaign
from swarm.spec import RunSpec

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()
BLOCKS = re.findall(r"```toml\n(.*?)```", README, re.S)


def test_every_toml_block_is_valid_for_what_it_configures():
    assert BLOCKS
    for block in BLOCKS:
        data = tomllib.loads(block)
        if "colours" in data:
            check_legend(data)
        elif set(data) == {"radio"}:
            config_from_mapping(data["radio"])
        elif "campaign" in data:
            assert parse_campaign(block).runs()
        elif "project" in data:
            assert "swarm.algorithms" in data["project"]["entry-points"]
        else:
            RunSpec.from_mapping(data)


def test_quick_start_has_exactly_the_two_marked_commands():
    for marker in ("<!-- ci:main -->", "<!-- ci:test -->"):
        after = README.split(marker, 1)[1]
        block = re.match(r"\s*```bash\n(.*?)```", after, re.S)
        assert block and len(block.group(1).strip().splitlines()) == 1
