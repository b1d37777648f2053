"""A learned path records the trot controller it was learned under; a comparison walks every trajectory under
that trot unless the command line chooses another, and then says so: a path from a policy trained with
sagittal foot placement need not save without it."""
import dataclasses
from types import SimpleNamespace

from conftest import ROOT, commanded, learned_set
from cyberdog import config as C
from cyberdog.analysis.extract import rollout_provenance
from cyberdog.core.learned_set import LearnedPath, LearnedSet
from cyberdog.core.trajectories import SampledTrajectory
from cyberdog.evaluation.recorded_trot import (controller_note, made_under, note_controllers, note_searched_trot,
                                               recorded_trot, searched_trot, walk_under_recorded_trot, with_trot)

PLACED = dataclasses.replace(C.ControllerConfig(), sagittal_placement_gain=0.1)


def placed_env() -> C.EnvConfig:
    env = C.EnvConfig()
    return dataclasses.replace(env, walk=dataclasses.replace(env.walk, controller=PLACED))


def test_the_rollout_provenance_holds_the_policy_trot_controller():
    rollout = SimpleNamespace(mean_speed=1.2, fell=False, duration=10.0, energy=500.0)
    prov = rollout_provenance(rollout, placed_env(), {"seed": 3})
    assert prov["controller"] == dataclasses.asdict(PLACED)
    assert prov["controller"]["sagittal_placement_gain"] == 0.1
    assert prov["seed"] == 3


def test_the_record_survives_the_file_and_a_different_controller_is_named(tmp_path):
    path = commanded(1.2, 0.01, seed=3)
    path.provenance["controller"] = dataclasses.asdict(PLACED)
    learned_set(seed3=[path]).save(tmp_path)
    loaded = LearnedSet.load([tmp_path])
    (p,) = loaded.paths()
    assert p.recorded_controller["sagittal_placement_gain"] == 0.1

    logged = []
    notes = note_controllers(loaded, C.WalkConfig(), logged.append)  # walked without the placement
    assert notes == logged and len(notes) == 1
    assert "sagittal_placement_gain 0.1 recorded, 0 here" in notes[0]
    assert "--set controller.sagittal_placement_gain=0.1" in notes[0]
    assert "seed3" in notes[0]
    # walked under the recorded controller: nothing to say
    same = dataclasses.replace(C.WalkConfig(), controller=PLACED)
    assert note_controllers(loaded, same, logged.append) == []


def test_a_path_without_a_record_or_with_the_same_controller_gets_no_note():
    assert controller_note(None, C.ControllerConfig()) == ""
    assert controller_note(dataclasses.asdict(C.ControllerConfig()), C.ControllerConfig()) == ""
    assert note_controllers(learned_set(seed0=[commanded(1.0, 0.0, seed=0)]), C.WalkConfig(), print) == []
    # every differing field is named, booleans as they are
    other = dataclasses.replace(C.ControllerConfig(), gravity_compensation=False, speed_gain=2.0)
    note = controller_note(other, C.ControllerConfig())
    assert "gravity_compensation False recorded, True here" in note
    assert "speed_gain 2 recorded, 1 here" in note


def _placed_set(*seeds: int) -> LearnedSet:
    paths = {}
    for seed in seeds:
        path = commanded(1.0, 0.01, seed=seed)
        path.provenance["controller"] = dataclasses.asdict(PLACED)
        paths[f"seed{seed}"] = [path]
    return learned_set(**paths)


def _args(*overrides: str, config=None, no_recorded_trot=False) -> SimpleNamespace:
    return SimpleNamespace(overrides=list(overrides), config=config, no_recorded_trot=no_recorded_trot)


def test_a_comparison_walks_under_the_trot_its_learned_paths_share():
    logged = []
    walked = walk_under_recorded_trot(_args("pid.kp=[84,84,84]"), C.WalkConfig(), _placed_set(0, 3), logged.append)
    assert walked.controller == PLACED  # every trajectory of the comparison walks the paths' trot
    assert walked.pid == C.WalkConfig().pid and walked.gait == C.WalkConfig().gait  # nothing else changes
    assert len(logged) == 1 and "controller.sagittal_placement_gain=0.1" in logged[0]
    assert "--no-recorded-trot" in logged[0]
    # already walked under it: the config as it is, nothing said
    placed = dataclasses.replace(C.WalkConfig(), controller=PLACED)
    assert walk_under_recorded_trot(_args(), placed, _placed_set(0), logged.append) is placed
    assert len(logged) == 1


def test_a_trot_the_command_line_chose_wins_and_the_difference_is_noted(tmp_path):
    yaml_with_trot = tmp_path / "walk.yaml"
    yaml_with_trot.write_text("controller:\n  speed_gain: 1.0\n")
    yaml_without = tmp_path / "plain.yaml"
    yaml_without.write_text("pid:\n  kp: [60, 60, 60]\n")
    for args in (_args("controller.max_speed_correction=0.3"), _args(no_recorded_trot=True),
                 _args(config=yaml_with_trot)):
        logged = []
        walked = walk_under_recorded_trot(args, C.WalkConfig(), _placed_set(0), logged.append)
        assert walked.controller == C.ControllerConfig()
        assert len(logged) == 1 and "sagittal_placement_gain 0.1 recorded, 0 here" in logged[0]
    # a config file without a controller section does not choose the trot
    assert walk_under_recorded_trot(_args(config=yaml_without), C.WalkConfig(), _placed_set(0),
                                    print).controller == PLACED


def test_paths_of_different_trots_walk_as_configured_each_with_its_note():
    mixed = _placed_set(0)
    mixed.add(LearnedPath("seed1", commanded(1.0, 0.0, seed=1)))  # recorded without a trot: walked as configured
    logged = []
    assert recorded_trot(mixed) is None
    assert walk_under_recorded_trot(_args(), C.WalkConfig(), mixed, logged.append) == C.WalkConfig()
    assert len(logged) == 1 and "seed0" in logged[0]
    # a record holding a field this ControllerConfig no longer has, and lacking a newer one
    old = {k: v for k, v in dataclasses.asdict(PLACED).items() if k != "speed_ramp_time"}
    cfg = with_trot(C.WalkConfig(), {**old, "retired_gain": 2.0})
    assert cfg.controller == PLACED


def test_the_prototype_run_walks_every_trajectory_under_the_learned_trot(tmp_path, monkeypatch, capsys):
    """End to end: the common trajectory and the learned path of a `evaluate.py prototype` run both build their
    trot controller with the paths' recorded foot placement, and the run's config.yaml says so."""
    import evaluate
    from cyberdog.control import trot as trot_module

    _placed_set(0).save(tmp_path / "learned")
    built = []
    original = trot_module.TrotController.__init__

    def recording(self, cfg, *args, **kwargs):
        original(self, cfg, *args, **kwargs)
        built.append(cfg.controller)
    monkeypatch.setattr(trot_module.TrotController, "__init__", recording)
    out = tmp_path / "proto"
    assert evaluate.main(["prototype", "--learned", str(tmp_path / "learned"), "--speeds", "1.0",
                          "--prototype-distance", "0.2", "--prototype-run-up", "0", "--prototype-modes", "ideal",
                          "--no-prototype-reference", "--workers", "1", "--out", str(out)]) == 0
    assert "recorded under the trot controller controller.sagittal_placement_gain=0.1" in capsys.readouterr().out
    assert len(built) >= 3 and all(c == PLACED for c in built)  # learned, cycloid, straight line
    assert C.load_walked(out / "config.yaml").walk.controller == PLACED


def _shape(**provenance) -> SampledTrajectory:
    phase = [i / 8 for i in range(8)]
    return SampledTrajectory(phase, [0.0] * 8, [0.0] * 8, 0.2, 0.085, provenance)


def test_a_searched_shape_is_noted_where_it_walks_under_another_trot_than_it_was_searched_under():
    placed = _shape(walk_overrides=["controller.sagittal_placement_gain=0.1", "gait.lift_height=0.085"])
    assert searched_trot(placed) == dataclasses.asdict(PLACED)
    logged = []
    note = note_searched_trot(placed, C.WalkConfig(), logged.append)
    assert logged == [note] and "sagittal_placement_gain 0.1 searched, 0.0 here" in note
    assert "--set controller.sagittal_placement_gain=0.0" in note  # the search that would match this trot
    assert note_searched_trot(placed, dataclasses.replace(C.WalkConfig(), controller=PLACED), logged.append) == ""
    # a search from before the overrides were recorded: its command line had no --set, so the default trot
    old = _shape(command="python tools/optimize_trajectory.py --lift-height 0.085")
    assert searched_trot(old) == dataclasses.asdict(C.ControllerConfig())
    assert "0.0 searched, 0.1 here" in note_searched_trot(old, dataclasses.replace(C.WalkConfig(), controller=PLACED))
    # nothing recorded, or a --config the record does not hold: no claim either way
    for unknown in (_shape(), _shape(command="python tools/optimize_trajectory.py --config walk.yaml")):
        assert searched_trot(unknown) is None
        assert note_searched_trot(unknown, C.WalkConfig(), logged.append) == ""
    assert len(logged) == 1


def test_the_prototype_run_walks_a_searched_shape_of_another_trot_under_its_own(tmp_path, capsys):
    import evaluate

    _placed_set(0).save(tmp_path / "learned")
    reference = tmp_path / "searched.json"
    SampledTrajectory.load(ROOT / "results" / "searched_shapes" / "optimized_trajectory_H0.10.json").save(reference)  # default trot
    assert evaluate.main(["prototype", "--learned", str(tmp_path / "learned"), "--speeds", "1.0",
                          "--prototype-distance", "0.2", "--prototype-run-up", "0", "--prototype-modes", "ideal",
                          "--prototype-reference", str(reference), "--workers", "1",
                          "--out", str(tmp_path / "proto")]) == 0
    assert "the searched shape walks under the trot it was searched under (sagittal_placement_gain 0.0" \
           in capsys.readouterr().out


def test_the_searched_shape_walks_the_prototype_under_the_trot_it_was_searched_under():
    """The prototype's reference is the best a user has of a searched shape: it walks under its own trot, the
    learned paths and the common trajectories under the paths' (`run_prototype(own_trot=...)`)."""
    from cyberdog.analysis.prototype import _walk_jobs
    from cyberdog.analysis.prototype_summary import REFERENCE
    from cyberdog.evaluation.recorded_trot import searched_controller

    default_searched = _shape(command="python tools/optimize_trajectory.py --lift-height 0.085")
    logged = []
    own = searched_controller(default_searched, PLACED, logged.append)
    assert own == {REFERENCE: C.ControllerConfig()} and "sagittal_placement_gain 0.0" in logged[0]
    assert searched_controller(default_searched, C.ControllerConfig()) == {}  # the same trot: nothing to change
    assert searched_controller(_shape(), PLACED) == {}  # nothing recorded: walked under the paths' trot
    base = dataclasses.replace(C.WalkConfig(), controller=PLACED)
    jobs = _walk_jobs({"cycloid": None, REFERENCE: default_searched}, (1.0,), base, [("hardware", 0)],
                      C.HARDWARE_LIKE, 20.0, 3.0, None, None, {}, 1.0, None, own)
    assert {j.trajectory_name: j.cfg.controller for j in jobs} == {"cycloid": PLACED, REFERENCE: C.ControllerConfig()}


def test_a_rewritten_path_records_the_trot_it_was_rewritten_under_and_keeps_its_sources_where_they_differ():
    placed = {"controller": dataclasses.asdict(PLACED), "seed": 3}
    same = made_under(placed, with_trot(C.WalkConfig(), placed["controller"]))
    assert same == placed  # rewritten under its own trot: nothing to add
    plain = made_under(placed, C.WalkConfig())  # a --set controller.* at the rewrite: the trot without placement
    assert plain["controller"] == dataclasses.asdict(C.ControllerConfig()) and plain["seed"] == 3
    assert plain["source_controller"]["sagittal_placement_gain"] == 0.1
    assert placed["controller"]["sagittal_placement_gain"] == 0.1  # the source's record is not changed
    assert made_under({}, C.WalkConfig())["controller"] == dataclasses.asdict(C.ControllerConfig())
