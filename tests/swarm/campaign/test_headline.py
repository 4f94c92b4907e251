"""The report's first-page finding (swarm.campaign.report.headline): one sentence naming the radio model's
largest and smallest effect on time to target and the algorithms' spread, computed from the runs."""

from __future__ import annotations

from types import SimpleNamespace

import pandas as pd

from swarm.campaign.report import readme
from swarm.campaign.report.headline import finding

ORDERS = {"algorithm": ["frontier", "greed", "minotaur"], "radio": ["global", "los"]}
TICKS = {("frontier", "global"): 2000, ("frontier", "los"): 2000, ("greed", "global"): 1800,
         ("greed", "los"): 2250, ("minotaur", "global"): 1700, ("minotaur", "los"): 2550}
"""Mean ticks to target per (algorithm, radio): frontier ignores the radio, Minotaur slows by half."""


def runs(ticks=TICKS, maps: int = 4, dnf: bool = False) -> pd.DataFrame:
    rows = []
    for (alg, radio), t in ticks.items():
        for rep in range(maps):
            jitter = 100 * (rep - (maps - 1) / 2)   # mean over the maps is t
            rows.append({"algorithm": alg, "radio": radio, "map": "building", "size": 50, "replicate": rep,
                         "status": "ok", "ttt_or_max": float(t + jitter), "success": not (dnf and rep == 0)})
    return pd.DataFrame(rows)


def test_the_sentence_names_the_largest_and_smallest_radio_effect_and_the_algorithms_spread():
    text = finding(runs(), ORDERS, 0.95)
    assert text == ("Over 4 maps (mean time to 95 % explored), the radio model moved minotaur's time from 170 s "
                    "under global to 255 s under los (+50 %) but frontier's only by +0 % (los), and the algorithms "
                    "ranged from minotaur (170 s) to frontier (200 s) under global radio.")


def test_runs_that_never_reached_the_target_are_said_to_count_at_the_limit():
    assert "counted at their time limit" in finding(runs(dnf=True), ORDERS, 0.95)


def test_only_what_varies_is_said():
    one_radio = runs({k: v for k, v in TICKS.items() if k[1] == "global"})
    text = finding(one_radio, {"algorithm": ORDERS["algorithm"], "radio": ["global"]}, 0.95)
    assert "radio model" not in text and "ranged from minotaur (170 s) to frontier (200 s)." in text
    one_alg = runs({k: v for k, v in TICKS.items() if k[0] == "greed"})
    text = finding(one_alg, {"algorithm": ["greed"], "radio": ORDERS["radio"]}, 0.95)
    assert "greed's time from 180 s under global to 225 s under los (+25 %)." in text and "ranged" not in text
    same = runs({("greed", "global"): 1800})
    assert finding(same, {"algorithm": ["greed"], "radio": ["global"]}, 0.95) is None


def test_the_finding_opens_the_readme_with_its_figure():
    rep = SimpleNamespace(finding="Radio matters.", finding_figure=("Exploration time against radio model",
                                                                   "comm/against_radio.png"))
    text = readme._finding(rep)
    assert text.startswith("## Finding\n\n**Radio matters.**")
    assert "![Exploration time against radio model](comm/against_radio.png)" in text
    assert readme._finding(SimpleNamespace(finding=None, finding_figure=None)) == ""
    src = readme.render.__code__.co_names
    assert src.index("_head") < src.index("_finding") < src.index("_runs")


def test_no_difference_and_no_success_are_said_as_such():
    flat = runs({k: 2000 for k in TICKS})
    text = finding(flat, ORDERS, 0.95)
    assert "did not change the time (200 s under global)" in text and "all took 200 s under global radio" in text
    assert "+0 %" not in text
    none = flat.assign(success=False)
    assert finding(none, ORDERS, 0.98) == "No run reached 98 % explored within its time limit (4 maps)."


def test_a_radio_run_on_some_cells_only_is_compared_on_those_cells():
    """Global radio run on the 50-tile maps only (as an ablation's [[include]] does), materials everywhere,
    with 150-tile maps taking five times as long: the radio did nothing, and the sentence says so; the mean
    over all materials runs against global's over small maps would say global cut the time by two thirds."""
    rows = []
    for size, t in ((50, 1000.0), (150, 5000.0)):
        for radio in (("materials", "global") if size == 50 else ("materials",)):
            for rep in range(4):
                rows.append({"algorithm": "tnf", "radio": radio, "map": "cave", "size": size, "replicate": rep,
                             "status": "ok", "ttt_or_max": t, "success": True})
    text = finding(pd.DataFrame(rows), {"algorithm": ["tnf"], "radio": ["materials", "global"]}, 0.98)
    assert "did not change the time (100 s under materials)" in text, text
    algs = pd.DataFrame(rows).assign(radio="materials").drop_duplicates(["size", "replicate"])
    other = algs[algs["size"] == 50].assign(algorithm="greed", ttt_or_max=1500.0)
    text = finding(pd.concat([algs, other]), {"algorithm": ["tnf", "greed"], "radio": ["materials"]}, 0.98)
    assert "ranged from tnf (100 s) to greed (150 s)" in text, text
