"""The paper's action space (joint torques, Table 3) and what helps a torque policy learn: the drivers' damping
and the trot prior whose weight decays to exactly zero (DecAP). The contract of the torque-mode env (scaling,
limits, Table 4's ±45° stops), the prior's schedule in the env, the trainer, its checkpoints and the resume,
and the evaluation of the policy alone."""
import csv
from pathlib import Path

import numpy as np
import pytest
import torch
from tensordict import TensorDict

from conftest import metrics_rows, stop_after, tiny
from cyberdog import config as C
from cyberdog.control.trot import TrotController
from cyberdog.core import kinematics as kin
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.loop.walker import Walker
from cyberdog.rl.checkpoint import load_checkpoint
from cyberdog.rl.logger import COLUMNS, EpisodeLogger
from cyberdog.rl.rollout import load_actor, rollout
from cyberdog.rl.td3 import TD3, UpdateSettings
from cyberdog.rl.trainer import Trainer

TORQUE = dict(action_mode="torque", control_dt=0.01)  # 4 controller periods per agent step: quick tests


def torque_env(**kw) -> CyberDogEnv:
    return CyberDogEnv(C.EnvConfig(**{**TORQUE, **kw}), reward="stage1")


# ---- the torque-mode env's contract ---------------------------------------------------------------------
def test_the_action_is_the_joint_torque_scaled_by_table4s_limit():
    env = torque_env()
    env.reset(seed=0)
    action = np.linspace(-0.3, 0.3, 12)
    env.step(action)
    # every period of the step applied 25 N·m per unit action (joints inside the range: no end stop)
    np.testing.assert_allclose(env.walker.tau.view(), np.tile(25.0 * action, (env.decimation, 1)), atol=1e-9)


def test_no_torque_reaches_a_joint_beyond_the_limit_with_prior_and_damping():
    env = torque_env(prior_weight=1.0, joint_damping=3.0)
    env.reset(seed=0)
    for sign in (1.0, -1.0) * 10:
        env.step(np.full(12, sign))
    applied = env.walker.tau.view()
    assert np.abs(applied).max() <= env.cfg.walk.actuator.torque_limit + 1e-9
    assert np.abs(applied).max() > 20.0  # the limit was reached, not avoided


def test_the_joint_range_end_stop_holds_a_joint_pushed_at_full_torque():
    """Table 4's ±45°: a hip driven at the full 25 N·m for 0.6 s is caught by the end stop's spring a few
    degrees beyond the range (it swings in with speed); without the stop it turns on to the URDF limit."""
    q_stand = kin.standing_joint_angles(C.RobotConfig()).ravel()
    reach = {}
    for stiffness in (200.0, 0.0):
        env = torque_env(joint_stop_stiffness=stiffness, joint_stop_damping=2.0 if stiffness else 0.0,
                         fall_height=0.001, fall_tilt_deg=180.0)
        env.reset(seed=0)
        action = np.zeros(12)
        action[1] = -1.0  # LF hip
        q = []
        for _ in range(60):
            env.step(action)
            q.append(env.walker.reading.q[1])
        reach[stiffness] = np.abs(np.array(q) - q_stand[1]).max()
    assert np.deg2rad(45.0) < reach[200.0] <= np.deg2rad(45.0 + 15.0)
    assert reach[0.0] > np.deg2rad(90.0)


def _torque_run(hardware: C.HardwareConfig) -> tuple[np.ndarray, np.ndarray, list]:
    """Five agent steps of fixed random torques from reset(seed=4): observations, Eq. 7 energies, infos."""
    env = torque_env(hardware=hardware, observe_last_action=False, target_speed_range=())
    obs, _ = env.reset(seed=4)
    observed, energies, infos = [obs], [], []
    for a in np.random.default_rng(2).uniform(-0.3, 0.3, (5, 12)):
        obs, _, _, _, info = env.step(a)
        observed.append(obs)
        energies.append(info["step_energy_J"])
        infos.append(info)
    env.close()
    return np.array(observed), np.array(energies), infos


@pytest.mark.parametrize("effect", ["friction", "latency", "mass", "encoder_noise", "estimated_velocity"])
def test_each_hardware_effect_reaches_the_torque_envs_step(effect):
    """The hardware-like robot's effects act on the paper's torque agent as on the trot: friction, the command
    bus's latency and the mass draw change the physics (the joints' work), encoder noise and the Kalman speed
    change only what the policy observes (the physics, on the true state, is the ideal robot's)."""
    hw = {"friction": C.HardwareConfig(friction=True), "latency": C.HardwareConfig(latency_s=0.0025),
          "mass": C.HardwareConfig(mass_uncertainty=0.05),
          "encoder_noise": C.HardwareConfig(joint_angle_noise_std=0.002, joint_velocity_noise_std=0.05),
          "estimated_velocity": C.HardwareConfig(estimated_velocity=True, imu_noise=True)}[effect]
    obs0, e0, _ = _torque_run(C.HardwareConfig())
    obs, e, infos = _torque_run(hw)
    angles, velocity = slice(11, 23), slice(5, 8)  # the observation's joint angles and body linear velocity
    if effect in ("friction", "latency", "mass"):
        assert np.abs(e - e0).max() > 1e-3 * e0.max()  # the joints did other work
    else:
        np.testing.assert_allclose(e, e0, rtol=1e-12)  # the same physics
        seen = angles if effect == "encoder_noise" else velocity
        assert np.abs(obs[1:, seen] - obs0[1:, seen]).max() > 1e-4  # another observation
    if effect == "estimated_velocity":
        assert all(i["velocity_estimate"] is not None for i in infos)
        used = [i["forward_speed_used"] for i in infos]
        assert not np.allclose(used, [i["forward_speed"] for i in infos]) and np.ptp(used) > 1e-4  # it runs


def test_the_velocity_filter_follows_the_body_under_a_torque_policy():
    """With no trot controller the robot's velocity filter still runs: the speed the policy observes and the
    reward pays (`forward_speed_used`) follows the body's, as it does under the trot (a filter left at its
    reset would show a walking robot standing)."""
    env = CyberDogEnv(C.EnvConfig(action_mode="torque", joint_damping=3.0, prior_weight=1.0, target_speed=1.0,
                                  hardware=C.HardwareConfig(estimated_velocity=True, imu_noise=True)),
                      reward="stage1")
    env.reset(seed=0)
    used, true = [], []
    for _ in range(80):  # 2 s walked by the prior
        _, _, terminated, _, info = env.step(np.zeros(12))
        used.append(info["forward_speed_used"])
        true.append(info["forward_speed"])
    assert not terminated and np.mean(true[40:]) > 0.4
    assert np.sqrt(np.mean((np.array(used) - true) ** 2)) < 0.1


def test_joint_damping_is_motor_torque_whose_work_eq7_books():
    """The drivers' damping: −c·q̇ on the joint speed at each physics step (the drivers' rate), applied as motor
    torque, so that the damper's work is in the energy (a damper in the joint model instead would hide it)."""
    walker = Walker(C.WalkConfig(), TrotController(C.WalkConfig()), drive=False, joint_damping=3.0,
                    fall_height=0.0, fall_tilt=np.pi)
    for _ in range(21):  # the body settles: the joints move
        walker.step(np.zeros(12))
    p = walker.physics_traces()
    # a physics step's speed at its start is the one PyBullet reports after the step before (= Δq / physics_dt)
    np.testing.assert_allclose(p["tau"][1:], np.clip(-3.0 * p["dq"][:-1], -25.0, 25.0), atol=1e-9)
    assert np.abs(p["tau"]).max() > 0.1 and walker.energy() > 0.0  # with no action at all: the damper's work


def test_a_drawn_kd_scales_the_drivers_damping_and_the_next_episode_draws_anew():
    """Randomised over the drivers' kd, the torque env's damping is the drawn kd times the configured one (no PID
    runs under a torque policy: the damping is the drivers' kd), applied at every physics step as above."""
    env = torque_env(joint_damping=3.0, randomization=C.RandomizationConfig(kd_factor=(0.5, 1.5)))
    factors = []
    for seed in range(2):
        _, info = env.reset(seed=seed)
        factors.append(kd := info["robot_draw"]["kd_factor"])
        assert env.walker.joint_damping == pytest.approx(3.0 * kd)
        for _ in range(5):
            env.step(np.zeros(12))
        p = env.walker.physics_traces()
        np.testing.assert_allclose(p["tau"][1:], np.clip(-3.0 * kd * p["dq"][:-1], -25.0, 25.0), atol=1e-9)
    assert abs(factors[0] - factors[1]) > 0.01 and all(abs(f - 1.0) > 0.01 for f in factors)


def test_damping_and_prior_are_refused_outside_torque_mode():
    for field in ("joint_damping", "prior_weight"):
        with pytest.raises(ValueError, match=f"EnvConfig.{field}"):
            C.EnvConfig(action_mode="residual", **{field: 1.0})


# ---- the prior's schedule -------------------------------------------------------------------------------
def test_the_prior_weight_decays_linearly_to_exactly_zero():
    cfg = C.EnvConfig(action_mode="torque", prior_weight=1.0, prior_decay_steps=400)
    assert [cfg.prior_weight_at(k) for k in (0, 100, 200, 400, 401, 10 ** 9)] == [1.0, 0.75, 0.5, 0.0, 0.0, 0.0]
    assert C.EnvConfig(action_mode="torque", prior_weight=0.5).prior_weight_at(10 ** 9) == 0.5  # no decay
    held = C.EnvConfig(action_mode="torque", prior_weight=1.0, prior_decay_start=100, prior_decay_steps=400)
    assert [held.prior_weight_at(k) for k in (0, 100, 300, 500, 501)] == [1.0, 1.0, 0.5, 0.0, 0.0]


def test_a_saved_config_holding_the_trainers_progress_loads_where_it_changes_nothing():
    """The trainer's progress is no env setting: a saved config that lists it at the values that leave the decay
    as it is (0 steps done, 1 per step) loads as if it did not; other values are refused, naming the field."""
    saved = C.to_dict(C.ExperimentConfig())
    saved["env"].update(prior_steps_done=0, prior_step_stride=1)
    assert C.from_dict(C.ExperimentConfig, saved) == C.ExperimentConfig()
    for name, value in (("prior_steps_done", 100), ("prior_step_stride", 2)):
        other = C.to_dict(C.ExperimentConfig())
        other["env"][name] = value
        with pytest.raises(ValueError, match=f"EnvConfig.{name} must be absent"):
            C.from_dict(C.ExperimentConfig, other)


@pytest.mark.parametrize("stride", [1, 2])
def test_the_env_counts_the_decay_across_episodes_and_envs(stride):
    decay = 2 + 5 * stride  # the sixth step's weight is exactly 0
    env = torque_env(prior_weight=1.0, prior_decay_steps=decay)
    env.set_training_progress(2, stride)  # the trainer's progress, given at run time
    weights = []
    for episode in range(3):
        env.reset(seed=episode)
        for _ in range(2):
            weights.append(env.step(np.zeros(12))[4]["prior_weight"])
    expected = [max(0.0, 1.0 - (2 + stride * k) / decay) for k in range(6)]
    assert weights == expected and weights[-1] == 0.0


def test_with_the_prior_at_one_the_robot_gets_the_trot_torque_held_and_at_zero_nothing():
    env = torque_env(prior_weight=1.0)
    env.reset(seed=0)
    trot = env.walker.trot_torque()
    env.step(np.zeros(12))
    np.testing.assert_allclose(env.walker.tau.view(), np.tile(np.clip(trot, -25, 25), (env.decimation, 1)),
                               atol=1e-9)
    pure = torque_env(prior_weight=0.0)
    pure.reset(seed=0)
    pure.step(np.zeros(12))
    assert not pure.walker.tau.view().any()  # no controller under the paper's action


def test_the_prior_walks_the_robot_where_the_policy_alone_does_not():
    """What the prior is for: at weight 1 (and the drivers' damping) a zero action walks 3 s forward; without
    it nothing drives the legs and the robot sinks onto its end stops where it stands."""
    distance = {}
    for w in (1.0, 0.0):
        env = CyberDogEnv(C.EnvConfig(action_mode="torque", joint_damping=3.0, prior_weight=w), reward="stage1")
        env.reset(seed=0)
        for _ in range(120):
            assert not env.step(np.zeros(12))[2]
        distance[w] = env.walker.reading.base_position[0] - env.walker.start[0]
    assert distance[1.0] > 1.0 and abs(distance[0.0]) < 0.1


# ---- the trainer: the schedule over stage 1, checkpoints, resume, evaluation ------------------------------
PRIOR = ["env.action_mode=torque", "env.joint_damping=2.0", "env.prior_weight=1.0", "env.prior_decay_steps=200",
         "train.stage1.max_env_steps=300", "train.checkpoint_every=100"]


def test_a_prior_that_outlasts_stage1_is_refused():
    with pytest.raises(ValueError, match="prior_decay_steps"):
        tiny(PRIOR, "env.prior_decay_steps=400")
    with pytest.raises(ValueError, match="prior_decay_start"):
        tiny(PRIOR, "env.prior_decay_start=150")
    with pytest.raises(ValueError, match="prior_decay_steps"):
        tiny(PRIOR, "env.prior_decay_steps=0")


def test_the_prior_decays_over_stage1_is_saved_and_resumes_and_the_stage_ends_without_it(tmp_path):
    cfg = tiny(PRIOR)
    stop_after(Trainer(cfg, tmp_path / "run", stages=(1, 2), progress=False), 100)  # after its checkpoint at 100
    state = load_checkpoint(tmp_path / "run" / "checkpoint.pt")
    assert state["counters"]["stage_env_steps"] == 100 and state["prior_weight"] == pytest.approx(0.5)
    resumed = Trainer(cfg, tmp_path / "run", resume=True, progress=False)
    assert resumed.prior_weight == pytest.approx(0.5) and resumed.progress.stage_env_steps == 100
    resumed.run()
    rows = metrics_rows(tmp_path / "run")
    weights = [float(r["prior_weight"]) for r in rows if r["stage"] == "1"]
    assert weights[0] > 0.9 and all(a >= b for a, b in zip(weights, weights[1:]))  # falls across the resume
    assert all(float(r["prior_weight"]) == 0.0 for r in rows if r["stage"] == "2")
    assert {r["fell"] for r in rows} <= {"0", "1"}
    final = load_checkpoint(tmp_path / "run" / "stage1_final.pt")
    assert final["prior_weight"] == 0.0 and final["counters"]["stage_env_steps"] == 300
    assert torch.load(tmp_path / "run" / "stage2_final_actor.pt", weights_only=True)["prior_weight"] == 0.0


def test_the_evaluated_torque_policy_runs_with_no_trot_controller(tmp_path, monkeypatch):
    Trainer(tiny(PRIOR), tmp_path, stages=(1,), progress=False).run()
    actor = load_actor(tmp_path / "stage1_final_actor.pt")
    assert actor.config.env.prior_weight == 1.0  # trained with the prior ...
    calls = []
    monkeypatch.setattr(TrotController, "command", lambda *a, **k: calls.append(a) or pytest.fail("controller"))
    result = rollout(actor, speed=1.0, duration=0.3)
    assert calls == [] and len(result.traces["tau"]) > 0  # ... judged without it


def test_a_metrics_file_of_an_older_version_gains_the_new_columns_on_resume(tmp_path):
    old = COLUMNS[:-2]
    with open(tmp_path / "metrics.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=old)
        w.writeheader()
        for i in range(3):
            w.writerow({k: i for k in old})
    EpisodeLogger(tmp_path, rows=2, purge_step=0, tensorboard=False).close()
    with open(tmp_path / "metrics.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == list(COLUMNS) and len(rows) == 2
    assert rows[1]["episode"] == "1" and rows[1]["fell"] == "" and rows[1]["prior_weight"] == ""


# ---- the pull toward the trot's torque (TD3+BC's regulariser) and the critics' warm-up ---------------------
def _batch(n: int = 8, reference=None) -> TensorDict:
    g = torch.Generator().manual_seed(3)
    return TensorDict({"observation": torch.randn(n, 50, generator=g),
                       "action": torch.rand(n, 12, generator=g) * 2 - 1,
                       "next": {"observation": torch.randn(n, 50, generator=g),
                                "reward": torch.randn(n, 1, generator=g),
                                "done": torch.zeros(n, 1, dtype=torch.bool),
                                "terminated": torch.zeros(n, 1, dtype=torch.bool),
                                "trot_action": torch.rand(n, 12, generator=g) * 2 - 1 if reference is None
                                else reference}}, [n])


def test_the_imitation_term_is_the_distance_to_the_share_the_prior_no_longer_gives():
    agent = TD3(C.AgentConfig(hidden_sizes=(16,), trot_imitation=2.0), 50, 12)
    b = _batch()
    b["next", "trot_action"][3] = float("nan")  # no reference for this transition (e.g. a reset): left out
    with torch.no_grad():
        agent.actor_net.layers[-1][0].normal_()  # an actor that acts, not the near-zero initial one
        now = agent.actor(b.select("observation").clone())["action"]
        pulled = (agent.actor_loss(b, UpdateSettings.of(agent.cfg), prior_weight=0.75)
                  - agent.actor_loss(b, UpdateSettings.of(C.AgentConfig(hidden_sizes=(16,)))))
    keep = [i for i in range(8) if i != 3]
    expected = 2.0 * ((now[keep] - 0.25 * b["next", "trot_action"][keep]) ** 2).mean()
    assert float(pulled) == pytest.approx(float(expected), rel=1e-5)


def test_a_strong_pull_makes_the_actor_output_the_trot_torque():
    b = _batch(64)
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(64, 64), trot_imitation=1000.0, policy_delay=1, actor_lr=3e-3), 50, 12)
    for _ in range(300):
        agent.update(b, UpdateSettings.of(agent.cfg))
    with torch.no_grad():
        out = agent.actor(b.select("observation").clone())["action"]
    error = (out - b["next", "trot_action"]).abs().mean()
    assert error < 0.1 < (b["next", "trot_action"]).abs().mean()


@pytest.mark.parametrize("targets", [True, False])
def test_a_warm_up_with_targets_evaluates_the_actor_as_it_is(targets):
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16,), policy_delay=1), 50, 12)
    before = {k: v.clone() for k, v in agent.network_state().items()}
    stage = C.StageConfig(critic_warmup_updates=1, critic_warmup_targets=targets)
    agent.update(_batch(), UpdateSettings.of(agent.cfg, stage))
    after = agent.network_state()
    moved = {prefix: any(not torch.equal(before[k], after[k]) for k in before if k.startswith(prefix))
             for prefix in ("actor_network_params", "qvalue_network_params", "target_qvalue_network_params")}
    assert moved == {"actor_network_params": False, "qvalue_network_params": True,
                     "target_qvalue_network_params": targets}


def test_imitation_needs_the_reference_and_keeps_it_per_transition(tmp_path):
    with pytest.raises(ValueError, match="EnvConfig.trot_reference"):
        tiny("env.action_mode=torque", "agent.trot_imitation=1.0")
    cfg = tiny("env.action_mode=torque", "env.trot_reference=true", "train.stage2.trot_imitation=1.0",
               "train.stage1.max_env_steps=100", "train.stage2.max_env_steps=100")
    trainer = Trainer(cfg, tmp_path, progress=False)
    trainer.run()
    stored = trainer.rb[:]["next", "trot_action"]
    assert stored.shape == (100, 12) and torch.isfinite(stored).all() and stored.abs().max() <= 1.0
    assert load_checkpoint(tmp_path / "checkpoint.pt")["replay"]["data"]["next"]["trot_action"].shape == (100, 12)


# ---- the shipped torque policies --------------------------------------------------------------------------
TORQUE_RESULTS = Path(__file__).resolve().parents[1] / "results" / "torque"
# the tuning seeds' actors and, where shipped, those of the seeds the recipe was never tuned on
SHIPPED = sorted(TORQUE_RESULTS.glob("policy/seed*")) + sorted(TORQUE_RESULTS.glob("fresh/policy/seed*"))


def test_the_torque_recipe_ships_seeds_0_to_4():
    assert [f.name for f in sorted(TORQUE_RESULTS.glob("policy/seed*"))] == [f"seed{k}" for k in range(5)]


@pytest.mark.parametrize("folder", SHIPPED, ids=[f"{f.parent.parent.name}-{f.name}" for f in SHIPPED])
def test_the_shipped_torque_policies_walk_a_hardware_like_robot_alone_and_stage2_draws_less(folder, monkeypatch):
    """configs/torque.yaml's actors walk 10 s at 1.4 m/s on hardware-like draw 0 with no trot controller under
    them, within ±5 % of the command and without falling, and stage 2 draws less electrical energy per metre
    than stage 1 (the prior is exactly 0: no controller is even built a command)."""
    from cyberdog.analysis.policy_check import robot_env

    monkeypatch.setattr(TrotController, "command", lambda *a, **k: pytest.fail("a trot controller ran"))
    per_metre = []
    for stage in (1, 2):
        actor = load_actor(folder / f"stage{stage}_actor.pt")
        assert actor.config.env.action_mode == "torque" and actor.config.env.randomization.enabled
        env, hardware_robot = robot_env(actor.config.env, "hardware:0")
        r = rollout(actor, speed=1.4, duration=10.0, env_config=env, hardware_robot=hardware_robot)
        assert not r.fell and abs(r.mean_speed - 1.4) <= 0.05 * 1.4, (stage, r.mean_speed)
        per_metre.append(r.electrical_energy / r.distance)
    assert per_metre[1] < per_metre[0]
