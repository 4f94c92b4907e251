"""swarm.base.params.check_choice: a value that is not one of the allowed strings, whatever its type, is one
clear InvalidInput line (an array once raised numpy's ambiguous-truth ValueError instead; found by the
environment constructor fuzz test)."""

from __future__ import annotations

import numpy as np
import pytest

from swarm.base.errors import InvalidInput
from swarm.base.params import check_choice


@pytest.mark.parametrize("value", [np.array([1, 2]), np.array(["goal"]), ["goal"], 1, None, b"goal", 1.5])
def test_anything_but_an_allowed_string_is_one_line_naming_the_field(value):
    with pytest.raises(InvalidInput) as info:
        check_choice("action", value, ("goal", "velocity"))
    assert info.value.field == "action" and "'goal' | 'velocity'" in str(info.value) and "\n" not in str(info.value)


def test_an_allowed_string_is_returned():
    assert check_choice("action", "velocity", ("goal", "velocity")) == "velocity"
    assert check_choice("action", np.str_("goal"), ("goal", "velocity")) == "goal"
