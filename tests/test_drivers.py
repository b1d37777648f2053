"""The motor drivers (`cyberdog.core.drivers`, `Robot.drive`): the locomotion controller's command is held over
its period and the drivers close their PD on the joint state at every physics step; Eq. (7) is the integral
of the torques PyBullet received."""
import numpy as np
import pybullet
import pytest

from cyberdog import config as C
from cyberdog.control.trot import TrotController
from cyberdog.core import energy as en
from cyberdog.core.drivers import (MAX_DAMPING_STEP, MAX_HALVINGS, MAX_STIFFNESS_STEP, JointCommand,
                                   driver_physics_dt, driver_torque)
from cyberdog.core.pid import JointPID
from cyberdog.loop.walker import Walker, driver_rate_config
from cyberdog.sim.robot import Robot

CFG = C.WalkConfig()
N = CFG.sim.physics_substeps  # physics steps per controller period


def _sent_commands(walker: Walker) -> list:
    """The commands the walker's controller sends, in order (its `command` wrapped)."""
    sent, command = [], walker.controller.command
    walker.controller.command = lambda *a, **k: sent.append(command(*a, **k)) or sent[-1]
    return sent


def test_the_drivers_law_is_the_pid_on_the_state_then_plus_the_feedforward():
    rng = np.random.default_rng(0)
    pid = JointPID(kp=(60.0, 50.0, 40.0), ki=0.0, kd=(2.0, 3.0, 4.0), integral_limit=2.0, dt=0.0025,
                   torque_limit=25.0)
    for _ in range(50):
        q_t, q, dq_t, dq, ff, integral = (rng.normal(0.0, s, 12).tolist() for s in (0.3, 0.3, 5.0, 5.0, 3.0, 1.0))
        for i in (None, integral):
            command = JointCommand(q_t, dq_t, ff, pid.kp_list, pid.kd_list, i)
            pd = np.array(pid.kp_list) * (np.array(q_t) - q) + np.array(pid.kd_list) * (np.array(dq_t) - dq)
            want = np.clip(pd + (0.0 if i is None else np.array(i)), -25.0, 25.0) + ff  # the clamp before τ_ff
            np.testing.assert_allclose(driver_torque(command, q, dq, 25.0), want, rtol=1e-12, atol=1e-12)
    nan = driver_torque(command, [float("nan")] * 12, dq, 25.0)
    assert not any(np.isfinite(nan))  # the robot refuses it


def test_two_physics_steps_of_one_period_apply_different_torques_each_from_the_joint_state_then():
    """Within one controller period the command is held, and the drivers' torque at each physics step is their
    law on the joint state at that step's start: the two steps of a period differ where the joints move."""
    with Walker(CFG) as w:
        sent = _sent_commands(w)
        for _ in range(300):
            w.step()
        p, q = w.physics_traces(), w.physics_q.view()
        actuator = w.robot.actuator
        differ = []
        for k in range(250, 300):
            rows = range(k * N, (k + 1) * N)
            for row in rows:  # the speed at a step's start is the one PyBullet reports after the step before
                tau = driver_torque(sent[k], q[row].tolist(), p["dq"][row - 1].tolist(), actuator.torque_limit)
                want = actuator.joint_torque(tau, p["dq"][row - 1].tolist())[0]
                np.testing.assert_allclose(p["tau"][row], want, rtol=1e-9, atol=1e-9)
            differ.append(np.abs(p["tau"][k * N + 1] - p["tau"][k * N]).max())
    assert min(differ) > 0.05 and np.median(differ) > 0.5  # N·m: not one torque held over the period


def test_the_drivers_read_their_own_encoders_not_the_controllers_noisy_reading():
    """Encoder noise is on what the locomotion controller reads; the drivers close their PD on the true joint
    state (their own encoders, at their own rate)."""
    noisy = C.HardwareConfig(joint_angle_noise_std=0.01, joint_velocity_noise_std=0.5)
    with Walker(CFG, hardware=noisy) as w:
        sent = _sent_commands(w)
        for _ in range(200):
            w.step()
        p, q = w.physics_traces(), w.physics_q.view()
        row = 199 * N  # the last period's first physics step: the state read at the period's start
        truth = driver_torque(sent[199], q[row].tolist(), p["dq"][row - 1].tolist(), 25.0)
        np.testing.assert_allclose(p["tau"][row], w.robot.actuator.joint_torque(truth, p["dq"][row - 1].tolist())[0],
                                   rtol=1e-9, atol=1e-9)


def test_the_energy_is_the_integral_of_the_torques_pybullet_received():
    """Replay the torques the walker applied, one per physics step, in a second world: the same joint angles to
    the bit, and Σ|τ·ω|·physics_dt with the speeds PyBullet reports after each step is the walker's Eq. (7);
    the electrical energy likewise."""
    h = CFG.sim.physics_dt
    with Walker(CFG) as w:
        for _ in range(int(round(2.0 / w.dt))):  # 2 s of the trot at 1 m/s
            w.step()
        p, booked, electrical, q_end = w.physics_traces(), w.energy(), w.electrical_energy(), w.state.q
    omegas = []
    with Robot(CFG.robot, CFG.actuator, CFG.sim) as robot:
        c = robot.client
        for torque in p["tau"]:  # friction is off on the ideal robot: the motor torque is what the joint received
            c.setJointMotorControlArray(robot.body_id, robot.joint_ids, pybullet.TORQUE_CONTROL, forces=torque.tolist())
            c.stepSimulation()
            states = c.getJointStates(robot.body_id, robot.joint_ids)
            omegas.append([s[1] for s in states])
        q_replay = np.array([s[0] for s in states])
    omega = np.array(omegas)
    assert booked > 100.0  # the robot walked
    np.testing.assert_array_equal(q_replay, q_end)
    assert booked == pytest.approx(float(np.abs(p["tau"] * omega).sum()) * h, rel=1e-9)
    assert electrical == pytest.approx(en.electrical_energy(p["tau"], omega, h, CFG.actuator, CFG.energy), rel=1e-9)


def _held_drive(robot, command, added=None, damping=0.0):
    """Drivers that hold one torque over the period (the model before: the PD at the controller rate)."""
    q, dq = robot.joint_lists()
    tau = driver_torque(command, q, dq, robot.actuator.torque_limit) if command is not None else [0.0] * 12
    taus = [robot.physics_step(tau) for _ in range(robot.substeps)]
    return taus, [robot.joint_lists()[0]] * len(taus)  # (the angles are not used below)


def _ringing(kd: float, monkeypatch, held: bool = False) -> float:
    """The knees' torque power between 100 and 300 Hz over 2.5 s of a 1.4 m/s cycloid walk (after a 1.5 s
    start), per kd² (the D term's HF torque grows with its gain even without ringing) and per sample² (the
    walk's physics rate follows its gains). A held PD at kd = 4 rings at about half the controller rate; above
    300 Hz is the pattern of the held command itself."""
    if held:
        monkeypatch.setattr(Robot, "drive", _held_drive)
    cfg = C.replace(CFG, gait=C.replace(CFG.gait, speed=1.4), pid=C.replace(CFG.pid, kd=(kd,) * 3))
    with Walker(cfg) as w:
        for _ in range(int(round(4.0 / w.dt))):
            w.step()
        knees = w.physics_tau.view(int(round(1.5 / w.dt)) * w.substeps)[:, 2::3]
        physics_dt = w.physics_dt  # kd 4: a finer step than the default (driver_rate_config)
    monkeypatch.undo()
    power = (np.abs(np.fft.rfft(knees - knees.mean(axis=0), axis=0)) ** 2).sum(axis=1)
    f = np.fft.rfftfreq(len(knees), d=physics_dt)
    return float(power[(f >= 100.0) & (f < 300.0)].sum()) / len(knees) ** 2 / kd ** 2  # (N²: any physics rate)


def test_a_kd_4_walk_does_not_ring(monkeypatch):
    """With the drivers at the physics rate, kd = 4 N·m·s/rad puts no more 100–300 Hz torque into the knees,
    per unit of gain, than kd = 2 (measured: 0.5×, at the finer step its gains get); drivers that held the PD
    over the period rang there (20×)."""
    kd2, kd4 = _ringing(2.0, monkeypatch), _ringing(4.0, monkeypatch)
    assert kd4 < 1.5 * kd2
    assert _ringing(4.0, monkeypatch, held=True) > 5.0 * kd2  # the measure sees a ringing PD


def test_the_integral_term_is_advanced_once_per_controller_period_and_held_in_the_command():
    """The drivers have no integrator: with ki > 0 the controller advances the integral once per period, on its
    own reading, and sends it with the command; the drivers add it inside their clamp at every physics step."""
    cfg = C.replace(CFG, pid=C.replace(CFG.pid, ki=(20.0, 20.0, 20.0)))
    with Walker(cfg) as w:
        sent = _sent_commands(w)
        for _ in range(100):
            w.step()
        assert len(sent) == 100 and all(c.integral is not None for c in sent)
        assert sent[-1].integral == w.controller.pid.integral.tolist() and np.any(w.controller.pid.integral != 0)
    with pytest.raises(ValueError, match="dq"):
        TrotController(cfg).command(0.0, np.zeros(12))


J_ROTOR = CFG.robot.reflected_rotor_inertia


@pytest.mark.parametrize("kp, kd", [(60.0, 2.0), (30.0, 1.0), (84.0, 2.37), (120.0, 2.0), (60.0, 4.0),
                                    (120.0, 4.0), (400.0, 12.0)])
def test_the_physics_step_is_halved_until_the_drivers_pd_is_within_its_bounds(kp, kd):
    h0, period = CFG.sim.physics_dt, CFG.sim.controller_dt
    h = driver_physics_dt(h0, (kp, kp / 2, 0.0), (0.0, kd, kd / 3), J_ROTOR)  # the largest gain of each counts
    assert kd * h / J_ROTOR <= MAX_DAMPING_STEP and kp * h * h / J_ROTOR <= MAX_STIFFNESS_STEP
    assert h == h0 or not (kd * 2 * h / J_ROTOR <= MAX_DAMPING_STEP and kp * 4 * h * h / J_ROTOR
                           <= MAX_STIFFNESS_STEP)  # no finer than needed
    n = period / h
    assert abs(n - round(n)) < 1e-9  # a controller period is whole physics steps
    # the default PD, softer ones and the replay check's 1.4x stiffness keep the configured 800 Hz
    assert (h == h0) == (kp <= 84.0 and kd <= 2.37)


def test_the_driver_rate_rule_refuses_absurd_gains_and_needs_a_rotor():
    with pytest.raises(ValueError, match="need a physics step"):
        driver_physics_dt(0.00125, (60.0,), (2.0 * 2 ** (MAX_HALVINGS + 1),), J_ROTOR)
    assert driver_physics_dt(0.00125, (1e4,), (1e3,), 0.0) == 0.00125  # no rotor: no scale, the step stays
    with pytest.raises(ValueError, match="joint_inertia"):
        driver_physics_dt(0.00125, (60.0,), (2.0,), -1.0)


def test_a_walk_at_doubled_damping_steps_its_drivers_twice_as_often():
    cfg = C.replace(CFG, pid=C.replace(CFG.pid, kd=(4.0,) * 3))
    assert driver_rate_config(CFG) is CFG  # the default gains: the configured step
    with Walker(cfg) as w:
        assert w.physics_dt == CFG.sim.physics_dt / 2 and w.substeps == 2 * N
        assert w.cfg.sim.physics_dt == w.physics_dt and w.dt == CFG.sim.controller_dt
        w.step()
        assert len(w.physics_tau.view(0)) == 2 * N  # the energy integrates every one of them
    coarse = Robot(CFG.robot, CFG.actuator, CFG.sim)
    try:
        with pytest.raises(ValueError, match="physics step"):
            Walker(cfg, robot=coarse)
    finally:
        coarse.close()


def test_the_torque_modes_damping_sets_the_rate_and_the_pid_it_does_not_run_does_not():
    """Under a torque policy the drivers' law is their damping alone (kd with kp = 0): 3 N·m·s/rad needs 1.6 kHz
    as kd 4 does; the trot's PID, which does not run then, does not set the step, even when stiff."""
    stiff = C.replace(CFG, pid=C.replace(CFG.pid, kp=(240.0,) * 3))
    assert driver_rate_config(stiff, drive=False) is stiff  # no damping, no PD: the configured step
    assert driver_rate_config(CFG, joint_damping=3.0, drive=False).sim.physics_dt == CFG.sim.physics_dt / 2
    assert driver_rate_config(CFG, joint_damping=1.0, drive=False) is CFG  # kd·h/J = 0.17
    with Walker(CFG, drive=False, joint_damping=3.0) as w:
        assert w.substeps == 2 * N
