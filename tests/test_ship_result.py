"""tools/ship.py policy: the wall time of a stage in the shipped metadata is the training's, not the calendar's."""
from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
import torch

from cyberdog.metrics_csv import stage_summary

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("ship", ROOT / "tools/ship.py")
ship = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ship)


def phase_of(actor: Path) -> str:
    """The phase a test's stand-in actor file was written for."""
    return torch.load(actor, weights_only=True)["phase"]


def episode_rows(end_times, stage=2, length=400, rate=50.0):
    return [{"stage": str(stage), "wall_time_s": str(t), "env_steps_per_s": str(rate), "length": str(length),
             "window_mean_score": "1.0", "score": "2.0", "energy_J": "1000"} for t in end_times]


def test_a_resumed_stage_counts_its_pause_as_one_typical_episode():
    steady = [1000.0 + 10.0 * i for i in range(10)]  # 10 s per episode, the first ran 8 s before its end
    resumed = steady + [steady[-1] + 86_400 + 10.0 * i for i in range(1, 6)]  # continued a day later
    whole = stage_summary(episode_rows(steady), 2)
    assert whole["wall_time_s"] == 9 * 10.0 + 8.0 and whole["pauses_excluded"] == 0
    later = stage_summary(episode_rows(resumed), 2)
    assert later["episodes"] == 15 and later["env_steps"] == 6000
    assert later["wall_time_s"] == 14 * 10.0 + 8.0 and later["pauses_excluded"] == 1
    assert stage_summary(episode_rows(steady), 1) == {}


def test_no_shipped_result_names_a_path_of_the_machine_that_made_it():
    """Provenance travels: every text file under results/ names files relative to the repository (or by run
    folder), never an absolute path."""
    import re
    root = Path(__file__).resolve().parents[1] / "results"
    absolute = re.compile(r'["\s=](/(?:work|home|root|tmp|Users|mnt|data)/[^"\s]*)')
    found = [(str(f.relative_to(root)), m.group(1)) for f in root.rglob("*") if f.suffix in (".json", ".md", ".csv",
                                                                                            ".yaml", ".txt")
             for m in absolute.finditer(f.read_text(errors="replace"))]
    assert found == []


def test_portable_paths_are_relative_to_the_folder_or_name_the_run():
    from cyberdog.provenance import portable_command, portable_path
    assert portable_path("/repo/runs/s0/stage2_final_actor.pt", root="/repo") == "runs/s0/stage2_final_actor.pt"
    assert portable_path("/scratch/me/runs/long_s0/stage2_final_actor.pt", root="/repo") == \
        "long_s0/stage2_final_actor.pt"
    assert portable_command(["--out", "/repo/runs/x", "--result=/repo/r.json", "--speeds", "1.0"], root="/repo") == \
        "--out runs/x --result=r.json --speeds 1.0"


def test_a_recipes_seed_folder_ships_its_last_stage1_and_stage2_phases_and_every_phases_log(tmp_path):
    """configs/torque.yaml: main, speed and band end with stage 1, energy to energy4 with stage 2: the shipped
    stage-1 actor is band's, the stage-2 actor energy4's, and each phase's log and summary travel with them."""
    import csv

    import yaml

    from cyberdog import config as C

    seed = tmp_path / "seed7"
    C.write_phases(seed, C.load_preset(ROOT / "configs" / "torque.yaml"), 7)
    phases = (("main", 1), ("speed", 1), ("band", 1), ("energy", 2), ("energy2", 2), ("energy3", 2), ("energy4", 2))
    assert [(p.name, p.last_stage) for p in C.read_phases(seed)[0]] == list(phases)
    for phase, stage in phases:
        run = seed / phase
        run.mkdir()
        (run / f"stage{stage}_final.pt").write_bytes(phase.encode())  # the final agent: the phase is done
        torch.save({"actor": {}, "phase": phase}, run / f"stage{stage}_final_actor.pt")
        (run / "config.yaml").write_text(yaml.safe_dump({"train": {"seed": 7}, "phase": phase}))
        rows = [{**r, "fell": "0"} for r in episode_rows([1000.0 + 10.0 * i for i in range(5)], stage=stage)]
        with open(run / "metrics.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    out = tmp_path / "shipped"
    assert ship.main(["policy", str(seed), "--out", str(out), "--all-phases"]) == 0
    assert phase_of(out / "stage1_actor.pt") == "band" and phase_of(out / "stage2_actor.pt") == "energy4"
    assert yaml.safe_load((out / "config.yaml").read_text())["phase"] == "energy4"
    assert {f.name for f in out.glob("metrics_*.csv")} == {f"metrics_{name}.csv" for name, _ in phases}
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["seed"] == 7 and list(meta["phases"]) == [name for name, _ in phases]
    assert meta["phases"]["energy"]["stage2"]["env_steps"] == 2000 and meta["wall_time_s"] == 7 * (4 * 10.0 + 8.0)
    assert C.read_phases(out / "recipe_phases.yaml")[0] == C.read_phases(seed)[0]  # every phase's settings
    assert not C.is_lineage(out)  # not a folder to resume or extract as a lineage


def test_a_run_continued_from_a_shipped_actor_records_where_that_actor_is(tmp_path, monkeypatch):
    """--init-from: the continued run's start, relative to the repository, in metadata.json; a start that is not
    there is refused before anything is written."""
    import csv

    import pytest
    import yaml

    monkeypatch.chdir(tmp_path)
    run, start = Path("runs/gains/seed3"), Path("results/policy/seed3/band/stage2_actor.pt")
    run.mkdir(parents=True)
    start.parent.mkdir(parents=True)
    start.write_bytes(b"band")
    torch.save({"actor": {}, "phase": "gains"}, run / "stage2_final_actor.pt")
    (run / "config.yaml").write_text(yaml.safe_dump({"train": {"seed": 3}}))
    rows = episode_rows([1000.0 + 10.0 * i for i in range(3)])
    with open(run / "metrics.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with pytest.raises(SystemExit, match="no such file"):
        ship.main(["policy", str(run), "--out", "results/policy/seed3", "--force", "--init-from", "nowhere.pt"])
    assert not Path("results/policy/seed3/stage2_actor.pt").exists()
    assert ship.main(["policy", str(run), "--out", "results/policy/seed3", "--force", "--init-from", str(start)]) == 0
    meta = json.loads(Path("results/policy/seed3/metadata.json").read_text())
    assert meta["init_from"] == "results/policy/seed3/band/stage2_actor.pt" and meta["seed"] == 3
    assert phase_of(Path("results/policy/seed3/stage2_actor.pt")) == "gains" and start.read_bytes() == b"band"


def test_a_phase_placed_from_another_folder_ships_without_a_log_and_is_named(tmp_path):
    """A lineage continued from a kept `main` (its stage1_final.pt copied in, nothing else): the seed ships, the
    placed phase is listed and has no log or wall time; a lineage missing a phase's final agent does not ship."""
    import csv

    import yaml

    from cyberdog import config as C

    seed = tmp_path / "seed8"
    C.write_phases(seed, C.load_preset(ROOT / "configs" / "torque.yaml"), 8)
    (seed / "main").mkdir(parents=True)
    (seed / "main" / "stage1_final.pt").write_bytes(b"agent")
    for phase, stage in [(p.name, p.last_stage) for p in C.read_phases(seed)[0]][1:]:  # every phase after main
        run = seed / phase
        run.mkdir()
        (run / f"stage{stage}_final.pt").write_bytes(phase.encode())
        torch.save({"actor": {}, "phase": phase}, run / f"stage{stage}_final_actor.pt")
        (run / "config.yaml").write_text(yaml.safe_dump({"train": {"seed": 8}}))
        rows = [{**r, "fell": "0"} for r in episode_rows([1000.0, 1010.0], stage=stage)]
        with open(run / "metrics.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    (seed / "speed" / "stage1_final.pt").unlink()
    with pytest.raises(SystemExit, match="speed/stage1_final.pt"):
        ship.main(["policy", str(seed), "--out", str(tmp_path / "no"), "--all-phases"])
    assert not (tmp_path / "no").exists()
    (seed / "speed" / "stage1_final.pt").write_bytes(b"speed")
    out = tmp_path / "shipped"
    assert ship.main(["policy", str(seed), "--out", str(out), "--all-phases"]) == 0
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["placed_phases"] == ["main"] and meta["phases"]["main"] == {"stage": "1", "from": None, "placed": True}
    assert not (out / "metrics_main.csv").exists() and (out / "metrics_speed.csv").is_file()
    assert meta["wall_time_s"] == pytest.approx(sum(meta["phases"][p]["stage" + meta["phases"][p]["stage"]]
                                                    ["wall_time_s"] for p in list(meta["phases"])[1:]))
