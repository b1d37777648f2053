"""A learned path records the trot controller it was learned under, and an evaluation that walks it under
another says so: a path from a policy trained with sagittal foot placement need not save without it."""
import dataclasses
from types import SimpleNamespace

from conftest import commanded, learned_set
from cyberdog import config as C
from cyberdog.analysis.extract import rollout_provenance
from cyberdog.core.learned_set import LearnedSet
from cyberdog.evaluation.learned import controller_note, note_controllers

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
