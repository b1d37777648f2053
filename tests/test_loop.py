"""The one simulation loop (`cyberdog.loop.Walker`): every caller steps the same physics, and the energy it
reports is the Eq. (7) integral of the torques and speeds it applied."""
import ast
from pathlib import Path

import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.analysis.walk import walk
from cyberdog.core import energy as en
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.loop.walker import Walker

from conftest import walk_config

PACKAGE = Path(__file__).resolve().parents[1] / "cyberdog"


def test_env_with_zero_foot_offsets_walks_exactly_the_scripted_walk():
    """The env (foot mode, zero action) and `walk()` are the same loop: same energy and travel, to rounding."""
    env = CyberDogEnv(action_mode="foot", target_speed=1.0)
    try:
        env.reset(seed=0)
        energy = sum(env.step(np.zeros(12))[4]["step_energy_J"] for _ in range(40))  # 1 s
        x = env.walker.state.base_position[0] - env.walker.start[0]
        walk_cfg = env.cfg.walk
    finally:
        env.close()
    r = walk(walk_cfg, duration=1.0)
    assert r.energy > 10.0  # the robot did walk
    assert energy == pytest.approx(r.energy, rel=1e-9)
    assert x == pytest.approx(r.distance, rel=1e-9)


def test_walker_energy_is_eq7_of_its_own_torques_and_joint_displacements():
    """Over a physics step the drivers' torque is constant and the joint's work is τ·Δq: Eq. (7) is Σ|τ·Δq| per
    joint over the physics steps, with Δq read from the recorded joint angles, and the electrical energy takes
    the same mean speed Δq / physics_dt; the per-period traces are the periods' means, their power integrates
    to the same energy."""
    cfg = C.WalkConfig()
    dt, h, n = cfg.sim.controller_dt, cfg.sim.physics_dt, cfg.sim.physics_substeps
    with Walker(cfg, record=True) as w:
        for _ in range(300):
            w.step()
        p, tr = w.physics_traces(), w.traces()
        tau, q = w.physics_tau.view(), w.physics_q.view()
        assert tau.shape == (300 * n, 12) and q.shape == (300 * n + 1, 12) and np.array_equal(q[-1], w.state.q)
        assert np.array_equal(p["tau"], tau) and p["dq"] == pytest.approx((q[1:] - q[:-1]) / h, rel=1e-12)
        by_hand = float(np.sum(np.abs(tau * (q[1:] - q[:-1]))))
        assert w.energy() == pytest.approx(by_hand, rel=1e-9)
        assert w.energy(since=100) == pytest.approx(float(np.sum(np.abs(tau[100 * n:] * np.diff(q[100 * n:], axis=0)))),
                                                    rel=1e-9)
        assert w.electrical_energy() == pytest.approx(
            en.electrical_energy(p["tau"], p["dq"], h, cfg.actuator, cfg.energy), rel=1e-12)
        # per controller period: the mean torque, the mean speed, and a power whose integral is Eq. (7)
        assert tr["tau"].shape == tr["dq"].shape == tr["q"].shape == tr["power"].shape == (300, 12)
        assert tr["tau"] == pytest.approx(tau.reshape(300, n, 12).mean(axis=1), rel=1e-12, abs=1e-12)
        assert tr["dq"] == pytest.approx((q[n::n] - q[:-1:n]) / dt, rel=1e-9, abs=1e-9)
        assert float(tr["power"].sum()) * dt == pytest.approx(w.energy(), rel=1e-12)
        w.reset()
        assert w.steps == 0 and len(w.traces()["tau"]) == 0 and len(w.physics_traces()["tau"]) == 0


def test_walker_reset_restores_the_same_walk():
    cfg = C.WalkConfig()
    with Walker(cfg) as w:
        for _ in range(200):
            w.step()
        first = w.energy()
        w.reset()
        for _ in range(200):
            w.step()
        assert w.energy() == first


def _calls(tree: ast.AST, attribute: str) -> list[str]:
    return [ast.unparse(n.func) for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute) and n.func.attr == attribute]


def test_one_place_steps_the_robot_under_the_controller():
    """Only the walker steps the robot (`Robot.drive`, `step`, `physics_step`) and calls the trot controller's
    `command` and `driver_torque` (its `torque` is the two in one, for callers outside the loop); only the
    robot's drivers and the controller's one-instant form apply the drivers' law; and nothing replaces a
    method of the robot at run time."""
    steppers, torquers, patches, laws = set(), set(), [], set()
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text())
        rel = str(path.relative_to(PACKAGE))
        if any("robot" in c.lower() for name in ("step", "physics_step", "drive") for c in _calls(tree, name)):
            steppers.add(rel)
        if any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "driver_torque"
               for n in ast.walk(tree)):
            laws.add(rel)
        if any(c.endswith(("controller.torque", "ctrl.torque", "controller.command", "controller.driver_torque"))
               for name in ("torque", "command", "driver_torque") for c in _calls(tree, name)):
            torquers.add(rel)
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign):
                for target in node.targets:
                    if (isinstance(target, ast.Attribute) and target.attr in ("step", "read_state")
                            and "robot" in ast.unparse(target.value).lower()):
                        patches.append(f"{rel}: {ast.unparse(target)}")
    assert steppers == {"loop/walker.py"}
    # and the joint table's export, which asks the controller for one gait period's commands at its targets
    # without stepping any robot
    assert torquers == {"loop/walker.py", "control/gait_table.py"}
    assert laws == {"sim/engine.py", "control/trot.py"}
    assert patches == []



def test_the_controller_period_is_written_once():
    """One body of the period: in the walker only `_period` pushes the latency queue and hands the command to
    the drivers (`_actuate`, the only caller of `Robot.drive`), and only it and `trot_torque` (the torque-mode
    prior, which does not step) ask the controller for a command; `run` and `step` both call it; no
    float/array twin of a per-period law (`*_list`) is left in the package."""
    tree = ast.parse((PACKAGE / "loop" / "walker.py").read_text())
    methods = {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    for name, expected in (("drive", {"_actuate"}), ("_actuate", {"_period"}), ("push", {"_period"}),
                           ("command", {"_period", "trot_torque"}), ("step", set()), ("physics_step", set())):
        callers = {m for m, node in methods.items() if any(c.endswith(f".{name}") for c in _calls(node, name))}
        assert callers == expected, (name, callers)
    assert {m for m, node in methods.items() if _calls(node, "driver_torque")} == {"trot_torque"}
    assert "self._period" in ast.unparse(methods["step"]) and "self._period" in ast.unparse(methods["run"])
    twins = [f"{p.relative_to(PACKAGE)}: {n.name}" for p in PACKAGE.rglob("*.py")
             for n in ast.walk(ast.parse(p.read_text())) if isinstance(n, ast.FunctionDef) and n.name.endswith("_list")]
    assert twins == []

def test_a_walker_without_its_body_trace_walks_the_same_and_refuses_a_walk_result():
    """The body trace is bookkeeping only (the env leaves it off): the same torques either way, and a result
    that needs it says so instead of failing on empty arrays."""
    from cyberdog.loop.result import walk_result

    cfg = C.WalkConfig()
    taus = []
    for body_trace in (True, False):
        with Walker(cfg, body_trace=body_trace) as w:
            for _ in range(100):
                w.step()
            taus.append(w.traces()["tau"].copy())
            if body_trace:
                assert walk_result(w, 1.0, fell=False).energy == pytest.approx(w.energy(), rel=1e-12)
            else:
                with pytest.raises(ValueError, match="body_trace=True"):
                    walk_result(w, 1.0, fell=False)
    assert np.array_equal(taus[0], taus[1])


def test_the_walkers_per_period_feedback_equals_the_state_snapshot():
    """The walker builds the trot's body feedback from the float reading, not from the RobotState arrays:
    the same four numbers, bit for bit, on a walk that sways and turns."""
    from cyberdog.control.trot import BodyFeedback
    from cyberdog.core import kinematics as kin

    walker = Walker(C.WalkConfig())
    for k in range(400):
        walker.step()
        if k % 50 == 49:
            r, s = walker.reading, walker.state
            want = BodyFeedback.from_state(s, walker.start)
            assert r.base_rpy[2] == want.yaw and r.base_position[1] - float(walker.start[1]) == want.lateral_offset
            assert r.base_linear_velocity_world[0] == want.forward_speed
            assert kin.lateral_velocity_body(r.base_quaternion, r.base_linear_velocity_world) == want.lateral_speed
            assert walker.state is s  # built once per period, when first asked
            assert np.array_equal(s.q, r.q) and np.array_equal(walker.q_rows.view()[-1], s.q)


@pytest.mark.parametrize("case", ["ideal", "end stop", "added torque", "hardware"])
def test_walker_run_equals_its_periods_one_by_one(case):
    """`Walker.run(n)` (the env's loop) is n calls of `step`, to the bit: on the ideal robot, with an end stop
    narrow enough to act in some periods, with an added torque, and on the hardware-like robot."""
    from cyberdog.control.joint_stop import JointStop
    cfg = walk_config(speed=1.2)
    stop = JointStop(cfg.robot, 0.12, 200.0, 1.0) if case == "end stop" else None
    hardware = C.HARDWARE_LIKE if case == "hardware" else None
    extra = np.linspace(-0.5, 0.5, 12) if case == "added torque" else None
    one, many = (Walker(cfg, joint_stop=stop, hardware=hardware, body_trace=False) for _ in range(2))
    applied = []
    for _ in range(30):  # 30 agent steps of 10 periods
        for _ in range(9):
            one.step(extra)
        applied.append((one.step(extra), many.run(10, extra)))
        assert np.array_equal(one.state.base_position, many.state.base_position)  # the snapshot of this period
    for a, b in applied:
        assert type(b) is np.ndarray and np.array_equal(a, b)
    assert one.steps == many.steps == 300 and one.reading == many.reading
    assert np.array_equal(one.tau.view(), many.tau.view()) and np.array_equal(one.q_rows.view(), many.q_rows.view())
    if stop is not None:  # the end stop acted in some periods
        assert any(stop.torque(q, np.zeros(12)) is not None for q in one.q_rows.view())
    with pytest.raises(ValueError, match="periods"):
        many.run(0)


def test_a_dropped_foot_shift_is_not_traced_as_applied_and_is_counted():
    """A shifted foot target out of the leg's reach sends the unshifted target, at the unshifted speed: the
    record (`last_foot_offsets`, the walker's foot_offsets trace) holds no shift for that leg, and the
    controller and the walk result count it."""
    from cyberdog.control.trot import BodyFeedback, TrotController
    from cyberdog.loop.result import walk_result
    cfg = C.WalkConfig()
    ctrl = TrotController(cfg)
    offsets = np.array([[0.0, 0.0, -0.5], [0.01, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # LF: 0.5 m down
    rates = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    ctrl.set_foot_offsets(offsets, rates)
    q = np.zeros(12)
    ctrl.command(0.5, q, BodyFeedback(forward_speed=1.0))
    assert ctrl.dropped_shifts == 1
    assert ctrl.last_foot_offsets[0] == (0.0, 0.0, 0.0) and ctrl.last_foot_offsets[1] == (0.01, 0.0, 0.0)
    plain = TrotController(cfg)
    plain.command(0.5, q, BodyFeedback(forward_speed=1.0))
    assert ctrl.last_foot_targets[0] == plain.last_foot_targets[0]  # what the robot got: the unshifted target
    ctrl.reset()
    assert ctrl.dropped_shifts == 0

    walker = Walker(cfg, TrotController(cfg), record=True)
    walker.controller.set_foot_offsets(offsets)
    for _ in range(40):
        walker.step()
    traced = walker.traces()["foot_offsets"]
    assert not traced[:, 0].any() and np.allclose(traced[:, 1], [0.01, 0.0, 0.0])
    assert walk_result(walker, 1.0, False).dropped_shifts == 40
