"""The observation of `CyberDog-v0` (Table 3's groups and the optional appended ones): its layout, size, bounds
and the typical magnitudes a learner scales its inputs by. Pure numpy and the configs: the learning layer reads
it without building an environment."""
from __future__ import annotations

import numpy as np

from cyberdog import config as C

# Observation layout: (name, size, low, high, typical magnitude). Bounds are generous physical limits, values
# are clipped to them; the typical magnitude is what a learner may divide by to bring inputs to order one.
OBSERVATION_LAYOUT = (
    ("body_height", 1, 0.0, 1.0, 0.3),  # m, z of the body centre
    ("lateral_offset", 1, -5.0, 5.0, 0.1),  # m, y from the straight line walked
    ("body_rpy", 3, -np.pi, np.pi, 0.2),  # rad, roll, pitch, yaw
    ("body_linear_velocity", 3, -10.0, 10.0, 1.0),  # m/s, body frame (true or estimated)
    ("body_angular_velocity", 3, -50.0, 50.0, 2.0),  # rad/s, body frame
    ("joint_angles", 12, -2 * np.pi, 2 * np.pi, 1.5),  # rad
    ("joint_velocities", 12, -100.0, 100.0, 10.0),  # rad/s
    ("joint_torques", 12, -100.0, 100.0, 10.0),  # N·m, motor torque applied over the last controller period
    ("target_speed", 1, 0.0, 10.0, 1.0),  # m/s
    ("gait_phase", 2, -1.0, 1.0, 1.0),  # sin, cos of the trot phase (LF leg)
)


# appended when `EnvConfig.observe_last_action` is set: the previous action, in action units (12 entries; 24 in
# action_mode "foot_torque")
LAST_ACTION_LAYOUT = (("last_action", 12, -1.0, 1.0, 1.0),)


# appended when `EnvConfig.observe_pd_stiffness` is set: the joint PD's kp over the default (PIDConfig.kp)
PD_STIFFNESS_LAYOUT = (("pd_stiffness", 1, 0.0, 5.0, 1.0),)
DEFAULT_KP = C.PIDConfig().kp[1]  # N·m/rad, the hip's: what a stiffness of 1 means


def observation_layout(cfg: C.EnvConfig | None = None) -> tuple:
    """The observation's (name, size, low, high, typical magnitude) groups for an env config."""
    last_action = ((("last_action", cfg.action_size, -1.0, 1.0, 1.0),) if cfg is not None and cfg.observe_last_action
                   else ())
    return (OBSERVATION_LAYOUT + last_action
            + (PD_STIFFNESS_LAYOUT if cfg is not None and cfg.observe_pd_stiffness else ()))


def observation_size(cfg: C.EnvConfig | None = None) -> int:
    """Entries of the observation: 50 (Table 3's groups), the action's size more (12; 24 in foot_torque) with
    `observe_last_action`, 1 more with `observe_pd_stiffness`."""
    return sum(n for _, n, _, _, _ in observation_layout(cfg))


def observation_typical_magnitude(cfg: C.EnvConfig | None = None) -> np.ndarray:
    """Typical magnitude of each observation entry (for input scaling in a learner), (`observation_size`,)."""
    return np.concatenate([np.full(n, m, dtype=np.float32) for _, n, _, _, m in observation_layout(cfg)])


def actor_observation_scale(cfg: C.EnvConfig | None = None, groups=()) -> np.ndarray:
    """The input scale of an actor that sees only the observation `groups` (names of the layout; () = all):
    the typical magnitude for the entries it sees, +inf for the others, so that s / scale is exactly 0 there
    (observations are clipped to finite bounds). Hiding inputs this way keeps every network the same shape
    as the full-observation one (checkpoints, the fast TD3 losses and rollouts need no other change)."""
    layout = observation_layout(cfg)
    names = [name for name, *_ in layout]
    unknown = [g for g in groups if g not in names]
    if unknown:
        raise ValueError(f"unknown observation group(s) {unknown} for the actor; this env's groups: {names}")
    scale = observation_typical_magnitude(cfg)
    if groups:
        start = 0
        for name, n, *_ in layout:
            if name not in groups:
                scale[start:start + n] = np.inf
            start += n
    return scale
