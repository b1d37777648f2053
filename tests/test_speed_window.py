"""The speed term over a window (RewardConfig.speed_window): r_v compares the mean speed with the mean command
over the window's last steps, restarts at each reset, and per step (the paper's) when the window is 0."""
import numpy as np
import pytest

from cyberdog import config as C
from cyberdog.core.rewards import speed_term
from cyberdog.envs.cyberdog_env import CyberDogEnv


def _walk(reward: C.RewardConfig, steps: int, seed: int = 0):
    """The env's speed term and, per step, the speed it used and the command, walking the trot."""
    env = CyberDogEnv(config=C.EnvConfig(target_speed=1.0), reward=reward)
    try:
        env.reset(seed=seed)
        terms, v, cmd = [], [], []
        for _ in range(steps):
            _, _, terminated, _, info = env.step(np.zeros(12))
            assert not terminated
            terms.append(info["reward_terms"]["speed"])
            v.append(info["forward_speed_used"])
            cmd.append(env.walker.commanded_speed)
        return np.array(terms), np.array(v), np.array(cmd), env
    except BaseException:
        env.close()
        raise


def test_windowed_speed_term_is_the_error_of_the_means():
    window_steps = 16  # 0.4 s at the agent step of 25 ms
    terms, v, cmd, env = _walk(C.RewardConfig(speed_window=0.4), steps=40)
    env.close()
    for k in range(40):
        lo = max(0, k + 1 - window_steps)
        expected = (cmd[lo:k + 1].mean() - v[lo:k + 1].mean()) ** 2
        assert terms[k] == pytest.approx(expected, rel=1e-9, abs=1e-15), k
    per_step = (cmd - v) ** 2
    assert not np.allclose(terms[window_steps:], per_step[window_steps:])  # the window changed the term


def test_window_restarts_at_reset_and_zero_is_per_step():
    terms, v, cmd, env = _walk(C.RewardConfig(speed_window=0.4), steps=20)
    try:
        env.reset(seed=1)
        _, _, _, _, info = env.step(np.zeros(12))
        first = (env.walker.commanded_speed - info["forward_speed_used"]) ** 2
        assert info["reward_terms"]["speed"] == pytest.approx(first, rel=1e-12)  # no step of the last episode
    finally:
        env.close()
    terms0, v0, cmd0, env0 = _walk(C.RewardConfig(), steps=20)
    env0.close()
    np.testing.assert_allclose(terms0, (cmd0 - v0) ** 2, rtol=1e-12)


@pytest.mark.parametrize("name, value, bad_values", [("speed_window", 0.4, (-0.1, float("nan"))),
                                                     ("speed_deadband", 0.03, (-0.01, 1.0, float("nan")))])
def test_speed_window_and_deadband_are_checked_and_reach_the_stage_reward(name, value, bad_values):
    for bad in bad_values:
        with pytest.raises(ValueError, match=name):
            C.RewardConfig(**{name: bad})
    stage = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, **{name: value}))
    assert getattr(C.stage_reward(stage), name) == value
    assert getattr(C.stage_reward(C.TrainConfig().stage2), name) == 0.0
    with pytest.raises(ValueError, match=name):  # a relabel keeps each stored speed term as it was
        C.TrainConfig(buffer_between_stages="relabel", stage2=stage)
    C.TrainConfig(buffer_between_stages="clear", stage2=stage)


def test_speed_window_class_keeps_the_last_steps():
    from cyberdog.core.rewards import SpeedWindow
    w = SpeedWindow(3)
    assert w.add(1.0, 2.0) == (1.0, 2.0)
    w.add(2.0, 2.0)
    w.add(3.0, 2.0)
    assert w.add(7.0, 5.0) == pytest.approx((4.0, 3.0))  # (2 + 3 + 7) / 3, (2 + 2 + 5) / 3
    w.reset()
    assert w.add(0.5, 1.0) == (0.5, 1.0)
    with pytest.raises(ValueError, match="steps"):
        SpeedWindow(0)


def test_speed_deadband_counts_only_the_error_beyond_its_share_of_the_command():
    from cyberdog.core.rewards import speed_term
    assert speed_term(1.36, 1.4, deadband=0.03) == 0.0  # 0.04 m/s off, inside 3 % of 1.4 m/s (0.042)
    assert speed_term(1.30, 1.4, deadband=0.03) == pytest.approx((0.1 - 0.042) ** 2)
    assert speed_term(1.50, 1.4, deadband=0.03) == pytest.approx((0.1 - 0.042) ** 2)  # too fast counts too
    assert speed_term(1.30, 1.4) == pytest.approx(0.01)  # 0: the paper's term
    with pytest.raises(ValueError, match="deadband"):
        speed_term(1.0, 1.0, deadband=1.0)


def test_env_applies_the_deadband_to_the_windows_means():
    band, window_steps = 0.03, 16
    terms, v, cmd, env = _walk(C.RewardConfig(speed_window=0.4, speed_deadband=band), steps=40)
    env.close()
    plain = []
    for k in range(40):
        lo = max(0, k + 1 - window_steps)
        error = abs(cmd[lo:k + 1].mean() - v[lo:k + 1].mean())
        plain.append(error ** 2)
        assert terms[k] == pytest.approx(max(0.0, error - band * abs(cmd[lo:k + 1].mean())) ** 2,
                                         rel=1e-9, abs=1e-15), k
    assert (terms > 0).any() and (terms < np.array(plain)).all()  # the start lags off the band: less, not 0


def test_speed_at_nominal_stride_pays_the_speed_loops_lengthening():
    """r_v on v · v_cmd / (v_cmd + c), c the trot's speed-loop correction: the speed the gait would walk at the
    stride its command asks for; off, the speed itself."""
    def walk(on: bool):
        return _trot_steps(C.EnvConfig(target_speed=1.0, action_mode="foot"),
                           C.RewardConfig(speed_at_nominal_stride=on),
                           ("forward_speed_used", "forward_speed_paid", "speed_loop_correction", "command", "speed"))

    on = walk(True)
    used, paid, c, cmd, term = on.T
    assert np.abs(c).max() > 0.01  # the loop did lengthen or shorten the stride (m/s)
    np.testing.assert_allclose(paid, used * cmd / (cmd + c), rtol=1e-12)
    np.testing.assert_allclose(term, (cmd - paid) ** 2, rtol=1e-9, atol=1e-15)
    off = walk(False)
    np.testing.assert_allclose(off[:, 1], off[:, 0], rtol=0)  # paid = used
    np.testing.assert_allclose(off[:, 4], (off[:, 3] - off[:, 0]) ** 2, rtol=1e-9, atol=1e-15)


def test_speed_at_nominal_stride_is_checked_and_reaches_the_stage_reward():
    with pytest.raises(ValueError, match="speed_at_nominal_stride"):
        C.RewardConfig(speed_at_nominal_stride=1)
    nominal = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, energy=0.0, speed_at_nominal_stride=True))
    assert C.stage_reward(nominal).speed_at_nominal_stride
    assert not C.stage_reward(C.TrainConfig().stage2).speed_at_nominal_stride
    with pytest.raises(ValueError, match="speed_at_nominal_stride"):
        C.TrainConfig(buffer_between_stages="relabel", stage2=nominal)


def test_a_relative_speed_term_pays_a_share_of_the_set_speed_the_same_at_every_command():
    """speed_term(per_speed=v_set): ((v_cmd − v_x) / v_set)², after the deadband; a 5 % error costs the same at
    1.0 and 1.4 m/s, where in m/s it costs 1.96x at 1.4."""
    assert speed_term(0.95, 1.0, per_speed=1.0) == pytest.approx(speed_term(1.33, 1.4, per_speed=1.4), rel=1e-12)
    assert speed_term(1.33, 1.4) == pytest.approx(1.96 * speed_term(0.95, 1.0), rel=1e-12)
    assert speed_term(1.2, 1.4, 0.02, per_speed=1.4) == pytest.approx(((0.2 - 0.028) / 1.4) ** 2, rel=1e-12)
    assert speed_term(1.39, 1.4, 0.02, per_speed=1.4) == 0.0  # inside the deadband
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="per_speed"):
            speed_term(1.0, 1.2, per_speed=bad)


def test_speed_relative_reaches_the_env_step_and_is_checked():
    """With reward.speed_relative the env's r_v is the error over the episode's set speed, not the ramped command."""
    with pytest.raises(ValueError, match="speed_relative"):
        C.RewardConfig(speed_relative=1)
    relative = C.StageConfig(reward=C.replace(C.STAGE2_REWARD, energy=0.0, speed_relative=True))
    with pytest.raises(ValueError, match="speed_relative"):
        C.TrainConfig(buffer_between_stages="relabel", stage2=relative)

    def walk(on: bool):
        return _trot_steps(C.EnvConfig(action_mode="foot"), C.RewardConfig(speed_relative=on),
                           ("forward_speed_paid", "command", "speed", "target_speed"))

    on, off = walk(True), walk(False)
    np.testing.assert_allclose(on[:, [0, 1, 3]], off[:, [0, 1, 3]], rtol=0)  # the same walk: the term does not act
    v_set = on[0, 3]
    assert v_set > 0 and (on[:, 3] == v_set).all()
    np.testing.assert_allclose(on[:, 2], ((on[:, 1] - on[:, 0]) / v_set) ** 2, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(off[:, 2], (off[:, 1] - off[:, 0]) ** 2, rtol=1e-9, atol=1e-15)
    assert (on[:, 1] < 0.5 * v_set).any()  # the ramp: r_v divides by the set speed, not the ramped command


def test_a_capped_speed_term_stops_growing_at_its_share_of_the_command():
    """RewardConfig.speed_cap: the error counts up to cap·|v_cmd| after the deadband, so a walk far off the command
    pays a bounded r_v per step; below the cap the term is the uncapped one."""
    assert speed_term(1.0, 1.2, 0.02, cap=0.15) == speed_term(1.0, 1.2, 0.02)  # 0.176 beyond: under 0.18
    assert speed_term(0.5, 1.2, 0.02, cap=0.15) == pytest.approx((0.15 * 1.2) ** 2, rel=1e-12)
    assert speed_term(0.0, 1.2, 0.0, per_speed=1.2, cap=0.15) == pytest.approx(0.15 ** 2, rel=1e-12)
    assert speed_term(2.0, 1.2, cap=0.15) == pytest.approx((0.15 * 1.2) ** 2, rel=1e-12)  # too fast: capped too
    assert speed_term(0.0, 1.2, cap=0.0) == pytest.approx(1.44, rel=1e-12)  # 0: no cap, the paper's term
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="cap"):
            speed_term(1.0, 1.2, cap=bad)
        with pytest.raises(ValueError, match="speed_cap"):
            C.RewardConfig(speed_cap=bad)


def test_speed_cap_reaches_the_env_step():
    """With reward.speed_cap the env's r_v is capped at the share of its ramped command, and nothing else moves."""
    columns = ("forward_speed_paid", "command", "speed")
    capped = _trot_steps(C.EnvConfig(action_mode="foot"), C.RewardConfig(speed_cap=0.1), columns)
    free = _trot_steps(C.EnvConfig(action_mode="foot"), C.RewardConfig(), columns)
    np.testing.assert_allclose(capped[:, :2], free[:, :2], rtol=0)  # the same walk
    error = np.abs(capped[:, 1] - capped[:, 0])
    np.testing.assert_allclose(capped[:, 2], np.minimum(error, 0.1 * np.abs(capped[:, 1])) ** 2, rtol=1e-9,
                               atol=1e-15)
    assert (error > 0.1 * np.abs(capped[:, 1])).any() and (error < 0.1 * np.abs(capped[:, 1])).any()
    assert (capped[:, 2] < free[:, 2]).any()


def _trot_steps(config: C.EnvConfig, reward: C.RewardConfig, columns: tuple[str, ...], steps: int = 60) -> np.ndarray:
    """The trot (a zero foot action) walked `steps` agent steps from seed 0, no fall allowed: per step the `info`
    entries named in `columns`, with "command" the ramped command and "speed" the unweighted r_v."""
    env = CyberDogEnv(config=config, reward=reward)
    try:
        env.reset(seed=0)
        out = []
        for _ in range(steps):
            _, _, terminated, _, info = env.step(np.zeros(12))
            assert not terminated
            row = {**info, "command": env.walker.commanded_speed, "speed": info["reward_terms"]["speed"]}
            out.append([row[c] for c in columns])
        return np.array(out, dtype=float)
    finally:
        env.close()
