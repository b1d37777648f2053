"""tools/ship_result.py: the wall time of a stage in the shipped metadata is the training's, not the calendar's."""
from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("ship_result", ROOT / "tools/ship_result.py")
ship_result = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ship_result)


def episode_rows(end_times, stage=2, length=400, rate=50.0):
    return [{"stage": str(stage), "wall_time_s": str(t), "env_steps_per_s": str(rate), "length": str(length),
             "window_mean_score": "1.0", "score": "2.0", "energy_J": "1000"} for t in end_times]


def test_a_resumed_stage_counts_its_pause_as_one_typical_episode():
    steady = [1000.0 + 10.0 * i for i in range(10)]  # 10 s per episode, the first ran 8 s before its end
    resumed = steady + [steady[-1] + 86_400 + 10.0 * i for i in range(1, 6)]  # continued a day later
    whole = ship_result.stage_summary(episode_rows(steady), 2)
    assert whole["wall_time_s"] == 9 * 10.0 + 8.0 and whole["pauses_excluded"] == 0
    later = ship_result.stage_summary(episode_rows(resumed), 2)
    assert later["episodes"] == 15 and later["env_steps"] == 6000
    assert later["wall_time_s"] == 14 * 10.0 + 8.0 and later["pauses_excluded"] == 1
    assert ship_result.stage_summary(episode_rows(steady), 1) == {}


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
