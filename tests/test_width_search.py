"""The lead over a search with a stance width, as the README and docs/results.md state it, is the shipped walks'
(results/figures_input/prototype_inset_reference.json, summarised as the prototype run summarises every run)."""
import json
from pathlib import Path

import pytest

from cyberdog.analysis import prototype_summary as ps

ROOT = Path(__file__).resolve().parents[1]
WALKS = ROOT / "results/figures_input/prototype_inset_reference.json"
SHAPE = ROOT / "results/searched_shapes/optimized_trajectory_H0.085_electrical_hardware_inset30.json"


def _learned_rows() -> dict:
    rows = ps.summary_rows(json.loads(WALKS.read_text()))
    return {r["speed_mps"]: r for r in rows if r["robot"] == "hardware" and r["trajectory"] == "learned"}


def test_the_reference_walked_is_the_shipped_shape_with_its_width():
    from cyberdog.core.trajectories import SampledTrajectory
    assert SampledTrajectory.load(SHAPE).foot_inset == pytest.approx(0.03)
    walks = json.loads(WALKS.read_text())
    assert {w["trajectory"] for w in walks} >= {"learned", "searched"} and not any(w["fell"] for w in walks)


def test_the_stated_leads_are_the_shipped_walks():
    rows = _learned_rows()
    assert sorted(rows) == [1.0, 1.2, 1.4]
    leads = " / ".join(f"+{rows[v]['battery_vs_searched_pct_mean']:.1f}" for v in (1.0, 1.2, 1.4))
    cis = " / ".join(f"{rows[v]['battery_vs_searched_pct_ci95']:.1f}" for v in (1.0, 1.2, 1.4))
    results = " ".join((ROOT / "docs/results.md").read_text().split())
    assert f"{leads} % (± {cis})" in results
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert f"by {leads.replace('+', '')} %" in readme
