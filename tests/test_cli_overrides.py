"""Both command lines take config overrides the same way: repeated --set flags and several values after one
--set add up, in order, and none is dropped."""
import pytest

from cyberdog import train_cli as train
from cyberdog import config as C
from cyberdog.evaluation.cli import parse_args as evaluate_args
from cyberdog.evaluation.commands import walk_config

SETS = [["--set", "gait.lift_height=0.1", "--set", "gait.straight_shape=trapezoid"],
        ["--set", "gait.lift_height=0.1", "gait.straight_shape=trapezoid"]]


@pytest.mark.parametrize("flags", SETS, ids=["repeated", "one flag"])
def test_evaluate_applies_every_override(flags):
    args = evaluate_args(["baselines", *flags])
    assert args.overrides == ["gait.lift_height=0.1", "gait.straight_shape=trapezoid"]
    cfg = walk_config(args)
    assert cfg.gait.lift_height == 0.1 and cfg.gait.straight_shape == "trapezoid"


@pytest.mark.parametrize("flags", SETS, ids=["repeated", "one flag"])
def test_train_parses_overrides_as_evaluate_does(flags):
    sets = [f.replace("gait.", "env.walk.gait.") for f in flags]
    args = train.parse_args(["--config", "configs/tiny.yaml", *sets])
    assert args.overrides == ["env.walk.gait.lift_height=0.1", "env.walk.gait.straight_shape=trapezoid"]


def test_a_later_assignment_wins():
    args = evaluate_args(["baselines", "--set", "gait.lift_height=0.1", "--set", "gait.lift_height=0.12"])
    assert walk_config(args).gait.lift_height == 0.12
    assert C.WalkConfig().gait.lift_height != 0.12


def test_compare_at_a_speed_without_a_learned_path_fails_before_any_walk(tmp_path, capsys):
    """`evaluate.py compare --speeds 0.8` with the shipped paths (1.0-1.4 m/s): one line naming the speeds that
    exist and what to do, exit 2, and no output folder."""
    import evaluate
    out = tmp_path / "out"
    assert evaluate.main(["compare", "--speeds", "0.8", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no learned path at 0.8 m/s" in err and "1, 1.2, 1.4 m/s" in err and "--policy-speed" in err
    assert not out.exists()


def test_extraction_outside_the_training_speeds_names_policy_speed_and_warns_when_it_is_used():
    from cyberdog.evaluation.cli import UsageError
    from cyberdog.evaluation.extraction import extraction_speeds
    env = C.EnvConfig(target_speed_range=(1.0, 1.4))
    with pytest.raises(UsageError, match="--policy-speed"):
        extraction_speeds(env, [0.8, 1.0], None)
    said = []
    assert extraction_speeds(env, [0.8], 0.8, log=said.append) == [0.8]
    assert len(said) == 1 and "extrapolation" in said[0]
    assert extraction_speeds(env, [1.2], 1.2, log=said.append) == [1.2] and len(said) == 1  # inside: no warning


def test_a_partial_section_in_a_file_changes_only_the_fields_it_names(tmp_path):
    """A YAML section that names one field keeps the parent's default for the rest: EnvConfig's walk lifts
    0.10 m (WalkConfig() alone: 0.15 m), and train.stage2 stays the energy stage."""
    f = tmp_path / "partial.yaml"
    f.write_text("env:\n  walk:\n    controller: {sagittal_placement_gain: 0.1}\n"
                 "train:\n  stage2: {max_env_steps: 5}\n")
    cfg = C.load(C.ExperimentConfig, f)
    default = C.ExperimentConfig()
    assert cfg.env.walk.controller.sagittal_placement_gain == 0.1
    assert cfg.env.walk.gait == default.env.walk.gait
    assert cfg.env.walk.gait.lift_height == 0.10
    assert cfg.train.stage2.max_env_steps == 5
    assert (cfg.train.stage2.reward, cfg.train.stage2.stop_score) == (C.STAGE2_REWARD, default.train.stage2.stop_score)
    # and the same as --set on the defaults
    assert cfg == C.override(default, ["env.walk.controller.sagittal_placement_gain=0.1",
                                       "train.stage2.max_env_steps=5"])
