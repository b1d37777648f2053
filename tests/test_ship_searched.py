"""tools/ship_searched.py: a searched-start recipe's walks run as the documented evaluate.py steps, are joined into
the files its table reads, and a re-make continues where one stopped."""
from __future__ import annotations

import importlib.util
import json
import subprocess
from pathlib import Path

import pytest
import yaml

from cyberdog import config as C

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("ship_searched", ROOT / "tools/ship_searched.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)
REAL_RUN = subprocess.run
N_STEPS = len(tool.steps(Path("own.json"), Path("eq7.json"), Path("inset.json")))  # the evaluate.py runs of one make


def step_of(cmd: list[str]) -> str:
    """The step a command walks for: its --out folder, or the folder above where it is a batch of seeds."""
    out = Path(after(cmd, "--out")[0])
    return out.parent.name if out.name.startswith("seed") else out.name


def seeds_walked(cmd: list[str]) -> list[str]:
    """The seeds of the path files (or of every file in the folders) after --learned."""
    files = [f for given in map(Path, after(cmd, "--learned"))
             for f in (sorted(given.glob("seed*.json")) if given.is_dir() else [given])]
    return sorted({f.name.split("_")[0] for f in files})


def after(cmd: list[str], flag: str) -> list[str]:
    """The arguments that follow `flag` up to the next option."""
    i, out = cmd.index(flag) + 1, []
    while i < len(cmd) and not cmd[i].startswith("--"):
        out.append(cmd[i])
        i += 1
    return out


@pytest.fixture
def fake_evaluate(monkeypatch, tmp_path):
    """evaluate.py steps record their command and write what a prototype or compare run writes, as far as the tool
    and tools/merge_walks.py read it (the run's --set settings in config.yaml); every other command runs for real.
    A step whose folder is named in `fail` fails, and every join where "join" is."""
    calls, fail = [], set()
    monkeypatch.chdir(tmp_path)  # the tool moves to the repository: back here after each test

    def run(cmd, *args, **kwargs):
        cmd = [str(c) for c in cmd]
        if "merge_walks.py" in cmd[1] and "join" in fail:
            return subprocess.CompletedProcess(cmd, 1)
        if "evaluate.py" not in cmd[1]:
            return REAL_RUN(cmd, *args, **kwargs)
        calls.append(cmd[1:])
        out = Path(after(cmd, "--out")[0])
        out.mkdir(parents=True, exist_ok=True)
        if step_of(cmd) in fail:
            return subprocess.CompletedProcess(cmd, 1)
        config = {"pid": {}}
        for setting in after(cmd, "--set") if "--set" in cmd else []:
            key, value = setting.split("=", 1)
            section, field = key.split(".")
            config.setdefault(section, {})[field] = yaml.safe_load(value)
        (out / "config.yaml").write_text(yaml.safe_dump(config))
        rows = [{"trajectory": t, "seed": seed, "pd_matched": "--pd-matched-from-default" in cmd,
                 "step": step_of(cmd)} for seed in seeds_walked(cmd) for t in ("learned", "cycloid")]
        (out / ("comparison.json" if cmd[2] == "compare" else "prototype.json")).write_text(json.dumps(rows))
        return subprocess.CompletedProcess(cmd, 0)

    monkeypatch.setattr(tool.subprocess, "run", run)
    return calls, fail


def paths_folder(tmp_path: Path) -> Path:
    learned = tmp_path / "learned"
    learned.mkdir()
    (learned / "seed40_1mps.json").write_text("{}")
    return learned


def test_the_walks_are_the_documented_steps_joined_into_the_tables_inputs(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    argv = ["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results", str(results)]
    assert tool.main(argv) == 0
    by_folder = {step_of(c): c for c in calls}
    assert list(by_folder)[:4] == ["prototype", "compare", "mujoco", "own"] and len(calls) == 20
    own = C.load_preset(ROOT / "configs/battery_searched.yaml").phases[-1].config.env.walk.gait.sampled_file
    assert after(by_folder["own"], "--prototype-reference") == [own]
    assert after(by_folder["compare"], "--reference") == [str(tool.EQ7_REFERENCE.relative_to(ROOT))]
    assert after(by_folder["mujoco"], "--set") == ["sim.engine=mujoco"]
    default = C.PIDConfig()
    assert after(by_folder["gains_kd2"], "--set") == [f"pid.kd=[{','.join([repr(default.kd[0] * 2)] * 3)}]"]
    assert after(by_folder["gains_kp0.5"], "--set") == [f"pid.kp=[{','.join([repr(default.kp[0] / 2)] * 3)}]"]
    recommanded = by_folder["gains_kp2_recommanded"]
    assert "--pd-matched-from-default" in recommanded and "--no-prototype-reference" in recommanded
    assert after(by_folder["gains_own_kd0.5"], "--prototype-reference") == [own]
    assert after(by_folder["inset"], "--prototype-reference") == [tool.INSET_REFERENCE]
    for tag, setting in (("payload3", "robot.payload=3.0"), ("friction0.4", "sim.ground_friction=0.4"),
                         ("friction1.2", "sim.ground_friction=1.2")):
        assert after(by_folder[f"conditions_{tag}"], "--prototype-reference") == [tool.INSET_REFERENCE]
        assert after(by_folder[f"conditions_{tag}"], "--set") == [setting]

    figures = results / "figures_input"
    assert [r["step"] for r in json.loads((figures / "prototype_searched_start.json").read_text())] == ["prototype"] * 2
    assert json.loads((figures / "comparison_searched_start.json").read_text())[0]["step"] == "compare"
    assert json.loads((figures / "prototype_searched_start_mujoco.json").read_text())[0]["step"] == "mujoco"
    assert json.loads((figures / "prototype_searched_start_own.json").read_text())[0]["step"] == "own"
    assert json.loads((figures / "prototype_searched_start_inset.json").read_text())[0]["step"] == "inset"
    gains = json.loads((figures / "gains_searched_start.json").read_text())
    assert sorted({(r["gain"], r["gain_scale"], r["pd_matched"]) for r in gains}) == \
        sorted((g, s, m) for g in ("kd", "kp") for s in (0.5, 2.0) for m in (False, True))
    own_gains = json.loads((figures / "gains_searched_start_own.json").read_text())
    assert {r["step"] for r in own_gains} == {f"gains_own_{g}{s}" for g in ("kp", "kd") for s in ("0.5", "2")}
    conditions = json.loads((figures / "conditions_searched_start.json").read_text())
    assert sorted({(r["step"], r["condition"], r["condition_value"]) for r in conditions}) == [
        ("conditions_friction0.4", "sim.ground_friction", 0.4), ("conditions_friction1.2", "sim.ground_friction", 1.2),
        ("conditions_payload3", "robot.payload", 3.0)]


def test_a_remake_keeps_the_steps_done_and_writes_nothing_when_one_fails(tmp_path, fake_evaluate):
    calls, fail = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    argv = ["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results", str(results)]
    fail.add("gains_kd2")
    with pytest.raises(SystemExit, match="failed"):
        tool.main(argv)
    assert not (results / "figures_input").exists()  # nothing shipped from a re-make that did not finish
    done = len(calls)
    fail.clear()
    assert tool.main(argv + ["--workers", "1"]) == 0  # --workers changes no walk: the steps done are kept
    again = [step_of(c) for c in calls[done:]]
    assert again[0] == "gains_kd2" and "prototype" not in again and len(again) == N_STEPS - done + 1
    n = len(calls)
    assert tool.main(argv + ["--force"]) == 0 and len(calls) == n + N_STEPS


def test_bad_input_is_refused_before_any_walk(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned = paths_folder(tmp_path)
    work = ["--work", str(tmp_path / "work")]
    with pytest.raises(SystemExit, match="not a folder of paths"):
        tool.main(["searched_start", "--learned", str(tmp_path), *work])
    with pytest.raises(SystemExit, match="--quick makes no result"):
        tool.main(["searched_start", "--learned", str(learned), *work, "--quick"])
    with pytest.raises(SystemExit):
        tool.main(["no_such_recipe", "--learned", str(learned), *work])
    assert calls == []


def test_nothing_is_shipped_when_a_join_fails(tmp_path, fake_evaluate):
    _, fail = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    fail.add("join")
    with pytest.raises(SystemExit, match="failed: joining"):
        tool.main(["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results",
                   str(results)])
    assert not (results / "figures_input").exists()  # no prototype file shipped beside the old gains files


def test_paths_changed_in_their_folder_are_walked_again(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    argv = ["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results", str(results)]
    assert tool.main(argv) == 0 and tool.main(argv) == 0 and len(calls) == N_STEPS  # the same paths: every step kept
    (learned / "seed40_1mps.json").write_text('{"re-picked": true}')
    assert tool.main(argv) == 0 and len(calls) == 2 * N_STEPS


def test_a_changed_reference_shape_walks_again_only_the_steps_that_walk_it(tmp_path, fake_evaluate, monkeypatch):
    calls, _ = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    inset, default = tmp_path / "inset.json", tmp_path / "default.json"
    for shape in (inset, default):
        shape.write_text("{}")
    monkeypatch.setattr(tool, "DEFAULT_PROTOTYPE_REFERENCE", default)
    argv = ["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results", str(results),
            "--inset-reference", str(inset)]
    assert tool.main(argv) == 0 and len(calls) == N_STEPS
    inset.write_text('{"searched": "again"}')
    walks_inset = ["inset", "conditions_payload3", "conditions_friction0.4", "conditions_friction1.2"]
    assert tool.main(argv) == 0 and [step_of(c) for c in calls[N_STEPS:]] == walks_inset
    default.write_text('{"searched": "again"}')  # the prototype run's own reference: every step naming none
    assert tool.main(argv) == 0
    assert sorted(step_of(c) for c in calls[N_STEPS + len(walks_inset):]) == sorted(
        ["prototype", "mujoco", "gains_kp0.5", "gains_kp2", "gains_kd0.5", "gains_kd2"])


def test_seeds_added_are_the_only_ones_walked_and_the_batches_are_joined(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned, results = paths_folder(tmp_path), tmp_path / "results"
    argv = ["searched_start", "--learned", str(learned), "--work", str(tmp_path / "work"), "--results", str(results)]
    assert tool.main(argv) == 0
    (learned / "seed41_1mps.json").write_text("{}")
    (learned / "seed41_1.2mps.json").write_text("{}")
    n = len(calls)
    assert tool.main(argv) == 0
    new = calls[n:]
    assert len(new) == N_STEPS  # every step once more: the batched ones for seed41 alone, compare for both
    assert {step_of(c): seeds_walked(c) for c in new if step_of(c) != "compare"} == \
        {step: ["seed41"] for step in map(step_of, new) if step != "compare"}
    assert seeds_walked(next(c for c in new if step_of(c) == "compare")) == ["seed40", "seed41"]
    shipped = json.loads((results / "figures_input/prototype_searched_start.json").read_text())
    assert [r["seed"] for r in shipped] == ["seed40", "seed40", "seed41", "seed41"]
    gains = json.loads((results / "figures_input/gains_searched_start.json").read_text())
    assert {r["seed"] for r in gains} == {"seed40", "seed41"} and len(gains) == 8 * 4


def test_a_seed_changed_or_gone_is_walked_again_or_left_out(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned, results, work = paths_folder(tmp_path), tmp_path / "results", tmp_path / "work"
    argv = ["searched_start", "--learned", str(learned), "--work", str(work), "--results", str(results)]
    assert tool.main(argv) == 0
    (learned / "seed41_1mps.json").write_text("{}")
    assert tool.main(argv) == 0
    assert sorted(p.name for p in (work / "prototype").iterdir()) == ["all_seeds", "seed40", "seed41"]
    (learned / "seed40_1mps.json").write_text('{"re-picked": true}')
    n = len(calls)
    assert tool.main(argv) == 0
    assert {tuple(seeds_walked(c)) for c in calls[n:] if step_of(c) != "compare"} == {("seed40",)}
    (learned / "seed41_1mps.json").unlink()
    n = len(calls)
    assert tool.main(argv) == 0 and [step_of(c) for c in calls[n:]] == ["compare"]  # its inputs changed
    assert sorted(p.name for p in (work / "prototype").iterdir()) == ["all_seeds", "seed40"]
    shipped = json.loads((results / "figures_input/prototype_searched_start.json").read_text())
    assert {r["seed"] for r in shipped} == {"seed40"}


def test_one_seeds_path_in_two_folders_is_refused(tmp_path, fake_evaluate):
    calls, _ = fake_evaluate
    learned = paths_folder(tmp_path)
    other = tmp_path / "other"
    other.mkdir()
    (other / "seed40_1mps.json").write_text("{}")
    with pytest.raises(SystemExit, match="seed40_1mps.json is in"):
        tool.main(["searched_start", "--learned", str(learned), str(other), "--work", str(tmp_path / "work"),
                   "--results", str(tmp_path / "results")])
    assert calls == []


def test_batches_walked_with_other_settings_are_not_joined(tmp_path):
    for name, pid in (("seed40", {}), ("seed41", {"kp": [30.0] * 3})):
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.yaml").write_text(yaml.safe_dump({"pid": pid}))
        (tmp_path / name / "prototype.json").write_text(json.dumps([{"seed": name}]))
    with pytest.raises(SystemExit, match="other settings"):
        tool.join_batches([tmp_path / "seed40", tmp_path / "seed41"], tmp_path / "all_seeds", "prototype.json")
    assert not (tmp_path / "all_seeds").exists()
