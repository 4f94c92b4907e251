"""The packet error curve: anchored at the sensitivity, 0 far above it, rising monotonically, 1 below it."""

from __future__ import annotations

import numpy as np
import pytest

from radio import RadioConfig
from radio.per import PacketErrorCurve
from swarm.base.errors import InvalidInput

MARGINS = np.linspace(-15.0, 15.0, 301)
LENGTHS = (20, 100, 1000, 4096, 20000)


def test_the_curve_passes_through_its_reference_point():
    for ref_per, ref_bytes in ((0.1, 4096), (0.1, 1000), (0.01, 20)):
        curve = PacketErrorCurve(ref_per, ref_bytes)
        assert curve.per(0.0, ref_bytes) == pytest.approx(ref_per, rel=1e-9)


def test_bpsk_bit_errors_match_the_textbook_figure():
    """BPSK on AWGN: BER 1e-5 needs Eb/N0 of about 9.6 dB (Q(sqrt(2 * 9.12)) = 7.8e-6 .. 1.0e-5)."""
    curve = PacketErrorCurve()
    margin = 9.6 - 10 * np.log10(curve.gamma_s)
    assert 7e-6 < float(curve.ber(margin)) < 1.1e-5


@pytest.mark.parametrize("nbytes", LENGTHS)
def test_per_is_zero_far_above_rises_monotonically_and_approaches_one_below(nbytes):
    curve = PacketErrorCurve()
    per = curve.per(MARGINS, nbytes)
    assert np.all(np.diff(per) <= 0.0), "PER never rises with the margin"
    assert per[MARGINS >= 6.0].max() < 1e-9
    assert per[MARGINS <= -8.0].min() > 0.99 and per[MARGINS <= -12.0].min() > 1.0 - 1e-6
    assert np.any((per > 0.05) & (per < 0.95)), "a smooth transition, not a step"


def test_longer_messages_are_lost_more_often():
    curve = PacketErrorCurve()
    rows = np.array([curve.per(MARGINS, n) for n in LENGTHS])
    assert np.all(np.diff(rows, axis=0) >= 0.0)
    at_sensitivity = {n: float(curve.per(0.0, n)) for n in LENGTHS}
    assert at_sensitivity[100] < 0.01 < at_sensitivity[1000] < at_sensitivity[4096] == pytest.approx(0.1)


def test_no_signal_is_a_certain_loss():
    curve = PacketErrorCurve()
    assert float(curve.ber(-np.inf)) == 0.5
    assert float(curve.per(-np.inf, 10)) == 1.0


@pytest.mark.parametrize("settings, name", [
    ({"per": "qam"}, "per"), ({"per_ref": 0.0}, "per_ref"), ({"per_ref": 1.0}, "per_ref"),
    ({"per_ref_bytes": 0}, "per_ref_bytes"), ({"per_ref_bytes": 1.5}, "per_ref_bytes"),
    ({"model": "global", "per": "bpsk"}, "per"), ({"model": "los", "per": "bpsk"}, "per"),
])
def test_bad_packet_error_settings_are_one_line_errors(settings, name):
    with pytest.raises(InvalidInput, match=name) as info:
        RadioConfig(**settings)
    assert "\n" not in str(info.value)


def test_per_settings_at_their_defaults_leave_the_canonical_form_alone():
    assert RadioConfig(per="off", per_ref=0.1, per_ref_bytes=4096).to_mapping() == RadioConfig().to_mapping()
    assert RadioConfig(per="bpsk").to_mapping()["per"] == "bpsk"
    assert RadioConfig(model="maes", per="bpsk").per == "bpsk"
