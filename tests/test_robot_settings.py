"""The robot's settings act on the simulated body or are refused: a payload changes the body (both engines);
`RobotConfig.total_mass` and the leg geometry state the URDF's, and a value that is not the URDF's is refused in one
line naming what would change the body."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.core.kinematics import standing_joint_angles
from cyberdog.sim import make_robot

CFG = C.WalkConfig()
PAYLOAD = 3.0  # kg


def _robot(engine: str, **robot):
    return make_robot(dataclasses.replace(CFG.robot, **robot), CFG.actuator,
                      dataclasses.replace(CFG.sim, engine=engine))


def _stand(robot, seconds: float = 1.0) -> float:
    """Hold the standing pose under a joint PD; the ground's force on the four feet then, N."""
    robot.reset()
    q_stand = standing_joint_angles(CFG.robot).reshape(12)
    for _ in range(round(seconds / robot.dt)):
        state = robot.read_state()
        robot.step(60.0 * (q_stand - state.q) - 2.0 * state.dq)
    return float(robot.foot_contact_forces().sum())


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_payload_weighs_on_the_feet(engine):
    plain, loaded = _robot(engine), _robot(engine, payload=PAYLOAD)
    try:
        assert loaded.total_mass() == pytest.approx(plain.total_mass() + PAYLOAD, abs=1e-9)
        g = CFG.sim.gravity
        assert _stand(loaded) == pytest.approx((plain.total_mass() + PAYLOAD) * g, rel=0.03)
        assert _stand(loaded) - _stand(plain) == pytest.approx(PAYLOAD * g, rel=0.1)
        loaded.set_mass_scale(1.1)  # a drawn mass scales the loaded body
        assert loaded.total_mass() == pytest.approx(1.1 * (plain.total_mass() + PAYLOAD), abs=1e-9)
    finally:
        plain.close()
        loaded.close()


def test_a_stated_total_mass_that_is_not_the_urdfs_is_refused_naming_the_payload():
    with pytest.raises(ValueError, match=r"links weigh 13\.577 kg.*robot\.payload") as err:
        _robot("pybullet", total_mass=16.0)
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="robot.payload"):
        _robot("mujoco", total_mass=16.0)


@pytest.mark.parametrize("payload", [-1.0, float("nan"), 20.0])
def test_payload_out_of_range_is_refused(payload):
    with pytest.raises(ValueError, match="RobotConfig.payload"):
        C.RobotConfig(payload=payload)


def test_a_loaded_walk_reports_its_mass_and_pays_for_it():
    """A 3 s cycloid trot with 3 kg on the body: the walk's cost of transport is per its loaded mass and its
    electrical energy per metre is higher than the unloaded walk's."""
    loaded_cfg = dataclasses.replace(CFG, robot=dataclasses.replace(CFG.robot, payload=PAYLOAD))
    plain, loaded = walk(CFG, duration=3.0), walk(loaded_cfg, duration=3.0)
    assert not plain.fell and not loaded.fell
    assert loaded.electrical_energy / loaded.distance > 1.05 * plain.electrical_energy / plain.distance
    mass = loaded.energy / (loaded.cost_of_transport * CFG.sim.gravity * loaded.distance)
    assert mass == pytest.approx(CFG.robot.total_mass + PAYLOAD, rel=1e-6)
    assert np.isfinite(plain.cost_of_transport)


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
@pytest.mark.parametrize("setting", [dict(l2=0.21), dict(l3=0.19), dict(l1=0.11), dict(abad_offset_x=0.25)])
def test_a_leg_geometry_that_is_not_the_urdfs_is_refused_naming_the_urdf(engine, setting):
    with pytest.raises(ValueError, match=r"leg geometry .* is not cyberdog\.urdf's.*robot\.urdf") as err:
        _robot(engine, **setting)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_a_foot_radius_that_is_not_the_urdfs_is_refused(engine):
    with pytest.raises(ValueError, match=r"foot_radius = 0\.03 m, but cyberdog\.urdf's foot spheres are 0\.0180 m"):
        _robot(engine, foot_radius=0.03)


def test_evaluate_walks_the_payload_asked_and_its_rows_show_the_mass(tmp_path):
    """`evaluate.py prototype --set robot.payload=3`: every row's mass_kg is the loaded body's, times its draw, and
    the output's config.yaml records the payload."""
    import json

    from conftest import commanded
    from cyberdog.core.learned_set import LearnedPath
    from cyberdog.evaluation import commands
    from cyberdog.evaluation.cli import parse_args

    path = LearnedPath("seed0", commanded(1.0, 0.0, 0)).save(tmp_path / "paths")
    out = tmp_path / "out"
    argv = ["prototype", "--learned", str(path), "--speeds", "1.0", "--prototype-distance", "0.3",
            "--prototype-run-up", "0", "--prototype-draws", "1", "--no-prototype-reference", "--workers", "1",
            "--set", f"robot.payload={PAYLOAD}", "--out", str(out)]
    assert commands.run(parse_args(argv), argv) == 0
    rows = json.loads((out / "prototype.json").read_text())
    assert rows and all(r["mass_kg"] == pytest.approx((CFG.robot.total_mass + PAYLOAD) * r["mass_scale"])
                        for r in rows)
    assert C.load_walked(out / "config.yaml").walk.robot.payload == PAYLOAD
