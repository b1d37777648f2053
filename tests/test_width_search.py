"""The lead over a search with a stance width, as the README and docs/results.md state it, is the shipped walks'
(results/figures_input/prototype_searched_pick_inset.json, summarised as the prototype run summarises every run)."""
import json
from pathlib import Path

import pytest

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis.searched_start_table import INSET_REFERENCE, SEARCHED_PICK

ROOT = Path(__file__).resolve().parents[1]
WALKS = ROOT / "results/figures_input" / SEARCHED_PICK.inset_source


def _learned_rows(seeds: set[str] | None = None) -> dict:
    walks = [w for w in json.loads(WALKS.read_text()) if seeds is None or w["seed"] in seeds]
    rows = ps.summary_rows(walks)
    return {r["speed_mps"]: r for r in rows if r["robot"] == "hardware" and r["trajectory"] == "learned"}


def _leads(rows: dict) -> tuple[str, str]:
    leads = " / ".join(f"+{rows[v]['battery_vs_searched_pct_mean']:.1f}" for v in (1.0, 1.2, 1.4))
    cis = " / ".join(f"{rows[v]['battery_vs_searched_pct_ci95']:.1f}" for v in (1.0, 1.2, 1.4))
    return leads, cis


def test_the_reference_walked_is_the_shipped_shape_with_its_width():
    from cyberdog.core.trajectories import SampledTrajectory
    assert SampledTrajectory.load(ROOT / INSET_REFERENCE).foot_inset == pytest.approx(0.03)
    walks = json.loads(WALKS.read_text())
    assert {w["trajectory"] for w in walks} >= {"learned", "searched"} and not any(w["fell"] for w in walks)
    # the pick's paths, every seed of its two fresh sets, and the same walks of them as its prototype run's
    pick = json.loads((WALKS.parent / SEARCHED_PICK.prototype_source).read_text())
    assert {w["seed"] for w in walks} == {w["seed"] for w in pick} == set().union(*SEARCHED_PICK.fresh_sets)
    key = lambda w: (w["seed"], w["speed_mps"], w["draw"])
    learned = {key(w): w["battery_used_pct"] for w in pick if w["trajectory"] == "learned"}
    assert {key(w): pytest.approx(w["battery_used_pct"], rel=1e-9) for w in walks if w["trajectory"] == "learned"} \
        == learned


def test_the_stated_leads_are_the_shipped_walks():
    first = _learned_rows({f"seed{n}" for n in range(20, 25)})
    pooled = _learned_rows()
    assert sorted(first) == sorted(pooled) == [1.0, 1.2, 1.4]
    results = " ".join((ROOT / "docs/results.md").read_text().split())
    for rows in (first, pooled):
        leads, cis = _leads(rows)
        assert f"{leads} % (± {cis}" in results
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert f"{_leads(pooled)[0].replace('+', '')} % ahead of a search that also narrows the stance" in readme
    assert all(r["battery_vs_searched_pct_mean"] - r["battery_vs_searched_pct_ci95"] > 0 for r in pooled.values())
