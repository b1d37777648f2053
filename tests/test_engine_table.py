"""The engines' table: each cell PyBullet / MuJoCo from a PyBullet input and its `_mujoco.json` twin."""
import json
import shutil
from pathlib import Path

import pytest

from cyberdog.analysis.engine_table import (HEADLINE_ROWS, POLICY_PYBULLET, PROTOTYPE, TABLE5, TORQUE,
                                            engine_markdown, twin)

SOURCE = Path(__file__).resolve().parents[1] / "results" / "figures_input"


def rows_of(table: str) -> dict[str, list[str]]:
    return {ln.split("|")[1].strip(): [c.strip() for c in ln.split("|")[2:-1]] for ln in table.splitlines()[2:]}


@pytest.fixture
def same_twice(tmp_path):
    """The PyBullet inputs with themselves as twins (the prototype's with the stiffness run's policy walks)."""
    for name in (*TABLE5, *PROTOTYPE, *TORQUE, POLICY_PYBULLET):
        shutil.copy(SOURCE / name, tmp_path / name)
        shutil.copy(SOURCE / name, tmp_path / twin(name))
    policy = [w for w in json.loads((SOURCE / POLICY_PYBULLET).read_text())
              if w["trajectory"] == "policy" and w["pd_scale"] == 1.0]
    (tmp_path / twin(PROTOTYPE[0])).write_text(json.dumps(json.loads((SOURCE / PROTOTYPE[0]).read_text()) + policy))
    return tmp_path


def test_the_same_walks_on_both_sides_give_equal_cells_and_no_gap(same_twice):
    rows = rows_of(engine_markdown(same_twice))
    assert set(HEADLINE_ROWS) <= set(rows)
    for label, cells in rows.items():  # "a / a", "a / a (+0.0)" or "k / k of n"
        assert all(len(set(c.replace("*", "").split(" (")[0].split(" of ")[0].split(" / "))) == 1 for c in cells)
        assert all(c.endswith("(+0.0)") for c in cells) == ("saving" in label or "D_t" in label), (label, cells)


def test_a_walk_that_fell_on_one_engine_is_noted_in_its_cell(same_twice):
    walks = json.loads((same_twice / twin(PROTOTYPE[0])).read_text())
    fell = next(w for w in walks if w["trajectory"] == "learned" and w["speed_mps"] == 1.2)
    fell["fell"] = True
    (same_twice / twin(PROTOTYPE[0])).write_text(json.dumps(walks))
    cells = rows_of(engine_markdown(same_twice))[HEADLINE_ROWS[1]]
    assert "fell 0 / 1" in cells[1] and "in the band" in cells[1] and "band" not in cells[0] + cells[2]
    assert cells[1].startswith("**") and "(+0.0)" in cells[0]  # the saving over the walks that count: no gap


def test_a_twin_of_other_paths_is_refused_and_no_twin_gives_no_table(same_twice):
    walks = json.loads((same_twice / twin(TABLE5[0])).read_text())
    for w in walks:
        if w["trajectory"] == "learned":
            w["lift_height_m"] += 0.01
    (same_twice / twin(TABLE5[0])).write_text(json.dumps(walks))
    with pytest.raises(ValueError, match="comparison_mujoco.json.*other learned paths"):
        engine_markdown(same_twice)
    (same_twice / twin(TABLE5[0])).unlink()
    assert engine_markdown(same_twice) is None


@pytest.mark.parametrize("recipe", ["searched_start", "searched_wide", "searched_pick"])
def test_the_searched_start_rows_are_each_engines_own_savings(same_twice, recipe):
    """Each recipe from the searched shape: its saving against the cheaper common trajectory and against the
    searched shape, each engine's from its own walks (a twin halving the learned battery moves both rows), in
    rows named by that recipe; another recipe's rows are not made from them."""
    from cyberdog.analysis import prototype_summary as ps
    from cyberdog.analysis.engine_table import SEARCHED_START_SAVING_ROW, SEARCHED_START_VS_ROW
    from cyberdog.analysis.searched_start_table import RECIPES

    shipped = next(r for r in RECIPES if r.name == recipe)
    others = [r for r in RECIPES if r is not shipped]
    walks = json.loads((SOURCE / PROTOTYPE[0]).read_text())  # stands in for the recipe's walks
    (same_twice / shipped.prototype_source).write_text(json.dumps(walks))
    cheaper = [{**w, "battery_used_pct": 0.5 * w["battery_used_pct"]} if w["trajectory"] == "learned" else w
               for w in walks]
    (same_twice / twin(shipped.prototype_source)).write_text(json.dumps(cheaper))
    rows = rows_of(engine_markdown(same_twice))
    assert not any(label.startswith(f"{other.label}:") for other in others for label in rows)
    for label, against in ((SEARCHED_START_SAVING_ROW, ps.COMMON), (SEARCHED_START_VS_ROW, (ps.REFERENCE,))):
        pybullet, mujoco = (sum(s := list(ps.battery_savings_by_seed(w, "hardware", 1.0, against).values())) / len(s)
                            for w in (walks, cheaper))
        assert rows[label.format(recipe=shipped.label)][0].split(" (")[0] == f"{pybullet:.1f} / {mujoco:.1f}".replace("-", "\u2212")
