"""Both command lines take config overrides the same way: repeated --set flags and several values after one
--set add up, in order, and none is dropped."""
import pytest

import train
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
