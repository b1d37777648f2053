"""A sweep seed's live status (cyberdog.sweeps.status): what it reads from a run's metrics.csv."""
import yaml

from cyberdog import config
from cyberdog.config import preset
from cyberdog.sweeps.status import SeedStatus

HEADER = "episode,stage,env_steps,score,window_mean_score\n"


def _lineage(tmp_path):
    """A lineage folder of two phases, `main` then `energy`, with `main` started."""
    run = tmp_path / "seed0"
    run.mkdir()
    (run / "phases.yaml").write_text(yaml.safe_dump({"seed": 0, "phases": [
        {"name": "main", "stage": 1, "config": {}}, {"name": "energy", "stage": 2, "from": "main", "config": {}}]}))
    (run / "main").mkdir()
    return run


def test_a_lineage_seed_counts_the_env_steps_of_its_finished_phases(tmp_path):
    """Each phase's metrics.csv counts from 0: the sweep's progress adds the finished phases' steps."""
    run = _lineage(tmp_path)
    (run / "main" / "metrics.csv").write_text(HEADER + "1,1,400,1.0,1.0\n2,1,800,2.0,1.5\n")
    st = SeedStatus(seed=0, run_dir=str(run))
    st.read_metrics()
    assert (st.env_steps, st.stage) == (800, 1)
    (run / "energy").mkdir()
    (run / "energy" / "metrics.csv").write_text(HEADER + "1,2,400,-3.0,-3.0\n")
    st.read_metrics()  # the lineage moved on: 800 of main + 400 of energy
    assert (st.env_steps, st.stage, st.best_score) == (1200, 2, {"1": 2.0, "2": -3.0})
    with open(run / "energy" / "metrics.csv", "a") as f:
        f.write("2,2,800,-2.0,-2.5\n3,2,12")  # a row still being written is not read
    st.read_metrics()
    assert st.env_steps == 1600
    fresh = SeedStatus(seed=0, run_dir=str(run))  # a resumed sweep reads it back the same
    fresh.read_metrics()
    assert fresh.env_steps == 1600


def test_a_lineage_s_phases_file_is_parsed_once_however_often_the_driver_polls(tmp_path, monkeypatch):
    """The driver reads every running seed's metrics twice a second; phases.yaml holds every phase's whole
    settings (tens of ms to parse), so it is read once per seed, and the phase folders still move on."""
    run = _lineage(tmp_path)
    (run / "main" / "metrics.csv").write_text(HEADER + "1,1,400,1.0,1.0\n")
    parsed = []
    read_phases = preset.read_phases
    counted = lambda folder: parsed.append(folder) or read_phases(folder)  # noqa: E731
    monkeypatch.setattr(preset, "read_phases", counted)
    monkeypatch.setattr(config, "read_phases", counted)
    st = SeedStatus(seed=0, run_dir=str(run))
    for _ in range(5):
        st.read_metrics()
    assert (len(parsed), st.env_steps) == (1, 400)
    (run / "energy").mkdir()
    (run / "energy" / "metrics.csv").write_text(HEADER + "1,2,400,-3.0,-3.0\n")
    for _ in range(5):
        st.read_metrics()
    assert (st.env_steps, st.stage) == (800, 2)
    assert len(parsed) == 1
