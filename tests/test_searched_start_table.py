"""The searched-start recipe's table keeps the seeds it was never tuned on apart from its tuning seeds, and each
group's cells are the prototype summary of that group's walks alone."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis import searched_start_table as sst
from cyberdog.analysis.markdown_cells import mean_ci

SHIPPED = Path(__file__).resolve().parents[1] / "results" / "figures_input" / "prototype.json"


def _walks() -> list[dict]:
    """The shipped battery prototype walks (seeds 0-4); seed 0 stands for the recipe's tuning seed."""
    walks = json.loads(SHIPPED.read_text())
    assert {"seed0", "seed1"} <= {w["seed"] for w in walks}
    return walks


def _rows(table: str) -> dict[str, list[str]]:
    return {cells[0]: cells[1:] for cells in ([c.strip() for c in ln.strip("|").split("|")]
                                                for ln in table.splitlines()[2:])}


def test_each_group_is_summarised_from_its_own_walks():
    walks = _walks()
    rows = _rows(sst.searched_start_markdown(walks))
    fresh = [w for w in walks if w["seed"] != "seed0"]
    expected = {r["speed_mps"]: r for r in ps.summary_rows(fresh)
                if r["robot"] == "hardware" and r["trajectory"] == "learned"}
    named = "seeds 1–4 (never tuned on)"
    assert rows[sst.VS_SEARCHED_ROW.format(seeds=named)] == [
        f"**{mean_ci(expected[v], 'battery_vs_searched_pct', '.1f', ' %', sign=True)}**" for v in sorted(expected)]
    tuned = {r["speed_mps"]: r for r in ps.summary_rows([w for w in walks if w["seed"] == "seed0"])
             if r["robot"] == "hardware" and r["trajectory"] == "learned"}
    assert rows[sst.SAVING_ROW.format(seeds="seed 0 (tuned on)")] == [
        f"**{mean_ci(tuned[v], 'battery_saving_pct', '.1f', ' %')}**" for v in sorted(tuned)]


def test_a_tuning_seeds_walks_never_reach_the_fresh_rows():
    walks = _walks()
    changed = copy.deepcopy(walks)
    for w in changed:
        if w["seed"] == "seed0" and w["trajectory"] == "learned":
            w["battery_used_pct"] *= 0.5
            w["electrical_energy_J"] *= 0.5
    before, after = _rows(sst.searched_start_markdown(walks)), _rows(sst.searched_start_markdown(changed))
    fresh = [k for k in before if "never tuned on" in k]
    tuned = [k for k in before if "(tuned on)" in k]
    assert fresh and tuned
    assert all(before[k] == after[k] for k in fresh)
    assert any(before[k] != after[k] for k in tuned)


def test_no_learned_walk_is_refused_in_one_line():
    with pytest.raises(ValueError, match="no learned path"):
        sst.searched_start_markdown([w for w in _walks() if w["trajectory"] != "learned"])


def test_the_table_is_made_only_where_its_walks_are_shipped(tmp_path):
    assert sst.make_table(tmp_path) is None
    (tmp_path / sst.SEARCHED_START.prototype_source).write_text(SHIPPED.read_text())
    assert sst.make_table(tmp_path).startswith(f"| `{sst.SEARCHED_START.config}`")


def _gains(walks: list[dict], gain: str, scale: float) -> list[dict]:
    return [{**w, "gain": gain, "gain_scale": scale, "pd_matched": False} for w in walks]


def test_the_gains_rows_hold_the_fresh_seeds_walks_alone():
    """A tuning seed's gains walks never reach the gains rows, which are named by the fresh seeds."""
    walks = _walks()
    fresh = [w for w in walks if w["seed"] != "seed0"]
    tuned = [{**w, "battery_used_pct": 0.5 * w["battery_used_pct"]} if w["trajectory"] == "learned" else w
             for w in walks if w["seed"] == "seed0"]
    only_fresh = _rows(sst.searched_start_markdown(walks, gains_walks=_gains(fresh, "kd", 2.0)))
    with_tuned = _rows(sst.searched_start_markdown(walks, gains_walks=_gains(fresh + tuned, "kd", 2.0)))
    label = "the saving at kd 2×, as commanded, seeds 1–4"
    assert label in only_fresh and only_fresh[label] == with_tuned[label]


def test_the_eq7_row_follows_its_group_whatever_seeds_the_comparison_holds():
    """The comparison's fresh seeds need not be the prototype's: its Eq. 7 row still joins the fresh group."""
    compared = json.loads((SHIPPED.parent / "comparison.json").read_text())
    assert {w["seed"] for w in compared if w["trajectory"] == "learned"} - {"seed0"}  # fresh seeds there
    table = sst.searched_start_markdown([w for w in _walks() if w["seed"] in ("seed0", "seed1")], compared)
    fresh_rows = [k for k in _rows(table) if k.startswith("learned against the shape searched on Eq. 7")]
    assert len(fresh_rows) == 2 and any("seed 1 (never tuned on)" in k for k in fresh_rows)


def test_the_readme_headline_names_the_fresh_seeds_and_holds_their_rows(tmp_path):
    """With the recipe's walks shipped (the battery walks relabelled seeds 20–24) the README's headline is made:
    its rows are the full table's, named by the seeds the walks hold; a re-commanded gains row is bold whole."""
    import shutil

    from cyberdog.analysis.engine_table import TWIN_SUFFIX
    from cyberdog.analysis.readme_tables import make_tables
    for f in SHIPPED.parent.glob("*.json"):
        if not f.name.endswith(TWIN_SUFFIX):
            shutil.copy(f, tmp_path / f.name)

    def relabel(walks: list[dict]) -> list[dict]:
        return [{**w, "seed": f"seed{int(w['seed'][4:]) + 20}"} if w.get("seed") else w for w in walks]

    walks = relabel(_walks())
    compared = relabel(json.loads((SHIPPED.parent / "comparison.json").read_text()))
    gains = [w for g, k in (("kp", 0.5), ("kp", 2.0), ("kd", 2.0)) for w in _gains(walks, g, k)]
    gains += [{**w, "pd_matched": True} for w in _gains(walks, "kd", 2.0)]
    recipe = sst.SEARCHED_START
    for name in (recipe.inset_source, recipe.conditions_source):  # the shipped seeds' runs: not these walks'
        (tmp_path / name).unlink(missing_ok=True)
    for name, rows in ((recipe.prototype_source, walks), (recipe.compare_source, compared),
                       (recipe.gains_source, gains),
                       (recipe.own_start_source, walks)):  # the own start: here the same reference as the prototype's
        (tmp_path / name).write_text(json.dumps(rows))
    tables = make_tables(tmp_path)
    full, head = _rows(tables["searched_start"]), _rows(tables["searched_start_headline"])
    named = [row.format(seeds="seeds 20–24 (never tuned on)") for row in (sst.SAVING_ROW, sst.VS_SEARCHED_ROW,
                                                                         sst.EQ7_ROW)]
    named += [sst.GAINS_ROW.format(gains=f"{g}, as commanded", seeds="seeds 20–24") for g in ("kp 0.5×", "kd 2×")]
    named.append("kd 2×, as commanded: the searched shape's saving, seeds 20–24")
    assert list(head) == named and all(head[k] == full[k] for k in head)
    assert "**the saving at kd 2×, re-commanded, seeds 20–24**" in full
    fresh = "seeds 20–24 (never tuned on)"
    vs_searched = [c.strip("*") for c in full[sst.VS_SEARCHED_ROW.format(seeds=fresh)]]
    assert full[sst.OWN_START_ROW.format(seeds=fresh)] == vs_searched
    saving = sst.SAVING_ROW.format(seeds="seeds 20–24 (never tuned on)")
    assert not any("seeds)" in c for c in full[saving])
    # a seed whose extraction found no path at 1 m/s: that cell says over how many seeds it is
    (tmp_path / recipe.prototype_source).write_text(json.dumps(
        [w for w in walks if not (w["seed"] == "seed23" and w["speed_mps"] == 1.0)]))
    cells = _rows(make_tables(tmp_path)["searched_start"])[saving]
    assert cells[0].endswith("(4 of 5 seeds)") and not cells[1].endswith("seeds)")
    # the Eq. 7 and gains inputs are optional: without them the headline holds the prototype's rows alone
    for name in (recipe.compare_source, recipe.gains_source, recipe.own_start_source):
        (tmp_path / name).unlink()
    assert list(_rows(make_tables(tmp_path)["searched_start_headline"])) == named[:2]


def test_the_gains_rows_are_named_by_the_seeds_the_gains_runs_walked():
    """Gains runs of fewer seeds than the prototype's: their rows name the seeds they walked (the headline's the
    same), and a seed of a set the table shows no prototype walks of is left out of the cells, not counted under
    another set's name."""
    walks = _walks()
    fresh = [w for w in walks if w["seed"] != "seed0"]
    three = _gains([w for w in fresh if w["seed"] != "seed4"], "kd", 2.0)
    rows = _rows(sst.searched_start_markdown(walks, gains_walks=three))
    assert "the saving at kd 2×, as commanded, seeds 1–3" in rows and not any("seeds 1–4" in r for r in rows
                                                                                if "kd 2×" in r)
    head, _ = sst.headline_rows(walks, three)
    assert "the saving at kd 2×, as commanded, seeds 1–3" in head
    recipe = sst.Recipe("r", "configs/battery_searched.yaml", "r", (frozenset({"seed1", "seed2", "seed3", "seed4"}),
                                                                    frozenset({"seed9"})), frozenset({"seed0"}), False)
    other = [{**w, "seed": "seed9", **({"battery_used_pct": 0.1 * w["battery_used_pct"]}
                                       if w["trajectory"] == "learned" else {})} for w in _gains(fresh, "kd", 2.0)
             if w["seed"] == "seed1"]  # a second set's seed, its gains walks shipped, its prototype walks not
    alone = _rows(sst.searched_start_markdown(walks, gains_walks=_gains(fresh, "kd", 2.0), recipe=recipe))
    mixed = _rows(sst.searched_start_markdown(walks, gains_walks=_gains(fresh, "kd", 2.0) + other, recipe=recipe))
    assert alone == mixed


def test_a_second_fresh_set_has_its_own_rows_and_the_pooled_rows_join_both(tmp_path):
    """Seeds 20-24 and 25-29 (the shipped battery walks relabelled twice): each set is summarised from its own
    walks, the pooled rows from all ten seeds', and the headline holds the first set's rows and the pooled ones;
    the gains rows are named by the sets their walks fall in."""
    walks = _walks()
    first = [{**w, "seed": f"seed{int(w['seed'][4:]) + 20}"} for w in walks]
    second = [{**w, "seed": f"seed{int(w['seed'][4:]) + 25}",
               **({"battery_used_pct": 0.9 * w["battery_used_pct"]} if w["trajectory"] == "learned" else {})}
              for w in walks]
    rows = _rows(sst.searched_start_markdown(first + second, gains_walks=_gains(first, "kd", 2.0)))

    def learned(group: list[dict]) -> dict:
        return {r["speed_mps"]: r for r in ps.summary_rows(group)
                if r["robot"] == "hardware" and r["trajectory"] == "learned"}

    for name, group in (("seeds 20–24 (never tuned on)", first), ("seeds 25–29 (never tuned on)", second),
                        ("seeds 20–29 (never tuned on, pooled)", first + second)):
        expected = learned(group)
        assert rows[sst.SAVING_ROW.format(seeds=name)] == [
            f"**{mean_ci(expected[v], 'battery_saving_pct', '.1f', ' %')}**" for v in sorted(expected)]
    assert rows[sst.SAVING_ROW.format(seeds="seeds 20–24 (never tuned on)")] != rows[
        sst.SAVING_ROW.format(seeds="seeds 25–29 (never tuned on)")]
    assert "the saving at kd 2×, as commanded, seeds 20–24" in rows
    head, optional = sst.headline_rows(first + second, _gains(first + second, "kd", 2.0))
    pooled = "seeds 20–29 (never tuned on, pooled)"
    assert head[:4] == (sst.SAVING_ROW.format(seeds="seeds 20–24 (never tuned on)"),
                        sst.VS_SEARCHED_ROW.format(seeds="seeds 20–24 (never tuned on)"),
                        sst.SAVING_ROW.format(seeds=pooled), sst.VS_SEARCHED_ROW.format(seeds=pooled))
    # then, up to six rows, the first set's Eq. 7 row and the saving at the gain that costs it most
    assert head[4:] == (sst.EQ7_ROW.format(seeds="seeds 20–24 (never tuned on)"),
                        sst.GAINS_ROW.format(gains="kd 2×, as commanded", seeds="seeds 20–29"))
    assert optional == set(head[4:])


def test_the_lead_over_the_shape_searched_with_a_narrower_stance_comes_from_its_own_run():
    """The inset run (the prototype run with that shape as its reference) gives each group it walked a row of the
    paths against it, named by its own seeds; the headline holds it beside the first set's and the pooled rows
    without pushing out the optional rows, and only where the inset run walked the same seeds."""
    walks = _walks()
    first = [{**w, "seed": f"seed{int(w['seed'][4:]) + 20}"} for w in walks]
    second = [{**w, "seed": f"seed{int(w['seed'][4:]) + 25}"} for w in walks]
    cheaper = [{**w, "battery_used_pct": 0.9 * w["battery_used_pct"]} if w["trajectory"] == ps.REFERENCE else w
               for w in first + second]  # a reference 10 % cheaper: a smaller lead than the searched shape's
    rows = _rows(sst.searched_start_markdown(first + second, inset_walks=cheaper))
    for name in ("seeds 20–24 (never tuned on)", "seeds 20–29 (never tuned on, pooled)"):
        group = [w for w in cheaper if name.endswith("pooled)") or int(w["seed"][4:]) < 25]
        expected = {r["speed_mps"]: r for r in ps.summary_rows(group)
                    if r["robot"] == "hardware" and r["trajectory"] == "learned"}
        inset = rows[sst.VS_INSET_ROW.format(seeds=name)]
        assert inset == [f"**{mean_ci(expected[v], 'battery_vs_searched_pct', '.1f', ' %', sign=True)}**"
                         for v in sorted(expected)]
        assert inset != rows[sst.VS_SEARCHED_ROW.format(seeds=name)]
    head, optional = sst.headline_rows(first + second, _gains(first + second, "kd", 2.0), inset_walks=cheaper)
    without, _ = sst.headline_rows(first + second, _gains(first + second, "kd", 2.0))
    pooled = "seeds 20–29 (never tuned on, pooled)"
    assert head[:6] == (without[0], without[1], sst.VS_INSET_ROW.format(seeds="seeds 20–24 (never tuned on)"),
                        without[2], without[3], sst.VS_INSET_ROW.format(seeds=pooled))
    assert head[6:] == without[4:] and optional == set(without[4:])
    # an inset run over the first set alone: its row there, none for the pooled seeds
    head, _ = sst.headline_rows(first + second, inset_walks=[w for w in cheaper if int(w["seed"][4:]) < 25])
    assert [r for r in head if "narrower" in r] == [
        sst.VS_INSET_ROW.format(seeds="seeds 20–24 (never tuned on)")]
    # an inset run over fewer seeds than the set: its row in the table is named by them, none in the headline
    some = [w for w in cheaper if w["seed"] in ("seed20", "seed21")]
    assert sst.VS_INSET_ROW.format(seeds="seeds 20–21 (never tuned on)") in _rows(
        sst.searched_start_markdown(first + second, inset_walks=some))
    assert not [r for r in sst.headline_rows(first + second, inset_walks=some)[0] if "narrower" in r]


def test_a_gains_run_that_walked_the_searched_shape_gives_its_saving_and_the_lead_over_it(tmp_path):
    """The gains rows against the searched shape come from the walks under those gains (the reference walked
    too), never from the default gains' walks."""
    walks = _walks()
    fresh = [w for w in walks if w["seed"] != "seed0"]
    at_kd2 = _gains(fresh, "kd", 2.0)
    rows = _rows(sst.searched_start_markdown(walks, gains_walks=at_kd2))
    vs = rows["kd 2×, as commanded: learned against the searched shape, seeds 1–4"]
    expected = {r["speed_mps"]: r for r in ps.summary_rows(fresh)
                if r["robot"] == "hardware" and r["trajectory"] == "learned"}
    assert vs == [mean_ci(expected[v], "battery_vs_searched_pct", ".1f", " %", sign=True) for v in sorted(expected)]
    searched = {r["speed_mps"]: r for r in ps.summary_rows(fresh)
                if r["robot"] == "hardware" and r["trajectory"] == ps.REFERENCE}
    assert [c.split(" (")[0] for c in rows["kd 2×, as commanded: the searched shape's saving, seeds 1–4"]] == [
        mean_ci(searched[v], "battery_saving_pct", ".1f", " %") for v in sorted(searched)]
    # a gains run without the reference: no such rows
    no_reference = _gains([w for w in fresh if w["trajectory"] != ps.REFERENCE], "kd", 2.0)
    assert not [k for k in _rows(sst.searched_start_markdown(walks, gains_walks=no_reference)) if "searched shape" in k
                and k.startswith("kd")]


def test_the_own_start_under_the_gains_gives_its_rows_alone_from_its_own_runs():
    """Gains runs with the recipe's own start as the reference: its saving and the paths' lead over it under each
    gain, named as its start, after the searched shape's rows; the paths' own rows are not repeated."""
    walks = _walks()
    fresh = [w for w in walks if w["seed"] != "seed0"]
    own = [{**w, "battery_used_pct": 1.1 * w["battery_used_pct"]} if w["trajectory"] == ps.REFERENCE else w
           for w in fresh]  # a dearer reference than the searched shape
    rows = _rows(sst.searched_start_markdown(walks, gains_walks=_gains(fresh, "kd", 2.0),
                                             own_start_gains_walks=_gains(own, "kd", 2.0)))
    label = "kd 2×, as commanded: {}, seeds 1–4"
    expected = {r["speed_mps"]: r for r in ps.summary_rows(own)
                if r["robot"] == "hardware" and r["trajectory"] == "learned"}
    assert rows[label.format("learned against its own start")] == [
        mean_ci(expected[v], "battery_vs_searched_pct", ".1f", " %", sign=True) for v in sorted(expected)]
    assert rows[label.format("learned against its own start")] != rows[label.format(
        "learned against the searched shape")]
    assert list(rows).count("the saving at kd 2×, as commanded, seeds 1–4") == 1
    assert list(rows)[-2:] == [label.format("its own start's saving"), label.format("learned against its own start")]


def test_each_recipe_has_its_own_table_from_its_own_inputs_and_tuning_seeds(tmp_path):
    """The wide-command recipe's walks (the shipped battery walks as seeds 30-34, its tuning seeds 0-4 beside them)
    make its own table, named by its preset, and no README headline (the README leads with the searched recipe);
    the searched recipe's table is not made from them, and its seed 1-4 walks are that recipe's tuning seeds, never a
    fresh row."""
    import shutil

    from cyberdog.analysis.engine_table import TWIN_SUFFIX
    from cyberdog.analysis.readme_tables import make_tables
    for f in SHIPPED.parent.glob("*.json"):
        if not f.name.endswith(TWIN_SUFFIX) and "_searched_" not in f.name:
            shutil.copy(f, tmp_path / f.name)
    walks = _walks()
    fresh = [{**w, "seed": f"seed{int(w['seed'][4:]) + 30}"} for w in walks]
    wide = sst.SEARCHED_WIDE
    (tmp_path / wide.prototype_source).write_text(json.dumps(walks + fresh))
    tables = make_tables(tmp_path)
    assert sst.SEARCHED_START.name not in tables and sst.SEARCHED_START.headline not in tables
    rows = _rows(tables[wide.name])
    assert tables[wide.name].startswith(f"| `{wide.config}`")
    assert wide.headline not in tables and not wide.in_readme and sst.SEARCHED_START.in_readme
    head, optional = sst.headline_of(tmp_path, wide)  # its rows, were it the README's
    assert [r for r in head if r not in optional] == [row.format(seeds="seeds 30–34 (never tuned on)")
                                                      for row in (sst.SAVING_ROW, sst.VS_SEARCHED_ROW)]
    assert sst.SAVING_ROW.format(seeds="seeds 0–4 (tuned on)") in rows
    expected = {r["speed_mps"]: r for r in ps.summary_rows(fresh)
                if r["robot"] == "hardware" and r["trajectory"] == "learned"}
    assert rows[sst.SAVING_ROW.format(seeds="seeds 30–34 (never tuned on)")] == [
        f"**{mean_ci(expected[v], 'battery_saving_pct', '.1f', ' %')}**" for v in sorted(expected)]


def test_the_readme_leads_with_the_pick_only_where_its_shipped_walks_clear_the_bar():
    """The two-lineage pick's bar for the README's lead: against the searched shape, +10 % or more with the 95 % CI
    above zero at every speed, over each of its shipped fresh sets (seeds 20-24, seeds 40-44). `in_readme` must say
    what those walks say."""
    walks = json.loads((SHIPPED.parent / sst.SEARCHED_PICK.prototype_source).read_text())
    learned = {w["seed"] for w in walks if w["trajectory"] == "learned"}
    assert learned == set().union(*sst.SEARCHED_PICK.fresh_sets) and len(sst.SEARCHED_PICK.fresh_sets) == 2
    clears = []
    for seeds in sst.SEARCHED_PICK.fresh_sets:
        rows = [r for r in ps.summary_rows([w for w in walks if w["robot"] == "hardware" and w.get("seed") in seeds])
                if r["trajectory"] == "learned"]
        assert sorted(r["speed_mps"] for r in rows) == [1.0, 1.2, 1.4]
        clears += [r["battery_vs_searched_pct_mean"] >= 10.0
                   and r["battery_vs_searched_pct_mean"] - r["battery_vs_searched_pct_ci95"] > 0 for r in rows]
    assert sst.SEARCHED_PICK.in_readme == all(clears)


def test_a_groups_seeds_are_named_run_by_run():
    """Two fresh sets pooled are named as two runs, never as one range that would take in the seeds between."""
    from cyberdog.analysis.markdown_cells import seeds_named

    assert seeds_named([f"seed{n}" for n in (*range(20, 25), *range(40, 45))]) == "seeds 20–24, 40–44"
    assert seeds_named(["seed9", "seed5", "seed6", "seed7", "seed8"]) == "seeds 5–9"
    assert seeds_named(["seed3", "seed5", "seed6", "seed9"]) == "seeds 3, 5–6, 9"
    assert (seeds_named(["seed0"]), seeds_named(["cycloid"])) == ("seed 0", "fresh seeds")


def test_a_recipe_whose_seed_sets_overlap_is_refused():
    with pytest.raises(ValueError, match="seed3, seed4 in two of its seed sets"):
        sst.Recipe("r", "configs/battery_searched.yaml", "r", (sst._seeds(1, 4), sst._seeds(3, 5)), frozenset(), False)
    with pytest.raises(ValueError, match="seed0 in two"):
        sst.Recipe("r", "configs/battery_searched.yaml", "r", (sst._seeds(0, 4),), frozenset({"seed0"}), False)


def test_an_empty_input_is_refused_by_the_table_and_the_headline_alike(tmp_path):
    recipe = sst.SEARCHED_PICK
    (tmp_path / recipe.prototype_source).write_text("[]")
    for make in (sst.make_table, sst.headline_of):
        with pytest.raises(ValueError, match="holds no walks"):
            make(tmp_path, recipe)
