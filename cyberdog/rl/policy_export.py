"""A trained actor as a robot takes it: a TorchScript and an ONNX graph from the raw observation to the action, and a
JSON sidecar that documents both.

The graph is the actor file's own network (`load_actor`: `TanhActor`, the observation divided by its scale, the
MLP, tanh) in `ExportedActor`: input `observation` (batch, n) float32, the observation as `CyberDogEnv` returns it;
outputs `action` (batch, 12; 24 in foot_torque mode) in [−1, 1], the PyTorch actor's action, and `action_si`, the
action times the scale the env applies (m of foot-target shift, N·m of torque). The ONNX file is written by
`torch.onnx.export(..., dynamo=True)`, the torch.export-based exporter (it needs onnxscript), opset `ONNX_OPSET`,
with a dynamic batch dimension and the weights inside the file; the TorchScript file by `torch.jit.trace`.
`export_policy` writes the three files and checks both graphs against the PyTorch actor on the observations of a
short rollout in the env (`recorded_observations`); the sidecar records the largest difference.

onnx, onnxruntime and onnxscript are the `export` extra (`pip install -e ".[export]"`), imported only here, when
an ONNX file is written or run.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import warnings
from pathlib import Path

import numpy as np
import torch
from torch import nn

from cyberdog.config import FOOT_MODES, JOINT_NAMES, LEG_NAMES
from cyberdog.envs.cyberdog_env import CyberDogEnv
from cyberdog.envs.observation import observation_layout
from cyberdog.provenance import portable_path
from cyberdog.rl.rollout import LoadedActor, load_actor

FORMAT = "cyberdog.exported_policy"
ONNX_OPSET = 18
PARITY_STEPS = 40  # agent steps of the rollout whose observations the export is checked on (1 s)
JOINTS = [f"{leg}_{joint}" for leg in LEG_NAMES for joint in JOINT_NAMES]
OBSERVATION_UNITS = {"body_height": "m", "lateral_offset": "m", "body_rpy": "rad", "body_linear_velocity": "m/s",
                     "body_angular_velocity": "rad/s", "joint_angles": "rad", "joint_velocities": "rad/s",
                     "joint_torques": "N·m", "target_speed": "m/s", "gait_phase": "-", "last_action": "action units",
                     "pd_stiffness": "hip kp / 60 N·m/rad"}
OBSERVATION_ENTRIES = {"body_rpy": ["roll", "pitch", "yaw"], "body_linear_velocity": ["x", "y", "z"],
                       "body_angular_velocity": ["x", "y", "z"], "gait_phase": ["sin", "cos"]}
OBSERVATION_NOTES = {
    "lateral_offset": "y from the straight line walked (the body's y at the reset)",
    "body_linear_velocity": "body frame: the truth, or the Kalman estimate on the hardware-like robot",
    "joint_torques": "the motor torque applied over the last controller period, its mean",
    "target_speed": "the commanded speed, ramped from 0 over the trot's speed_ramp_time after the reset",
    "gait_phase": "of LF's trot phase φ (0 at its lift-off): sin 2πφ, cos 2πφ",
    "last_action": "the previous action, as the actor gave it"}
ACTION_USE = {
    "foot": "a shift of the trot controller's foot target per leg (Δx, Δy, Δz; leg frame: x forward, y left, z up), "
            "ramped linearly from the previous action's shift over the control period; the trot (IK + PD + "
            "feedforward, the walk settings below) tracks the shifted path",
    "foot_torque": "the first 12: a shift of the trot controller's foot target per leg, as in foot mode; the last 12: "
                   "a joint torque the trot adds to its feedforward, held over the control period",
    "residual": "a joint torque added to the trot controller's, held over the control period",
    "torque": "the joint torque, held over the control period (no trot controller)"}


class ExportDependencyError(ImportError):
    """onnx, onnxruntime or onnxscript is missing; the message names the install command."""


def require_onnx():
    """(onnx, onnxruntime): imported here, or ExportDependencyError naming `pip install -e ".[export]"`."""
    try:
        import onnx
        import onnxruntime
        import onnxscript  # noqa: F401 (the dynamo exporter's translation needs it)
    except ImportError as err:
        missing = err.name or err
        raise ExportDependencyError(f"exporting a policy to ONNX needs onnx, onnxruntime and onnxscript ({missing} is "
                                    f"missing): pip install -e \".[export]\"") from None
    return onnx, onnxruntime


class ExportedActor(nn.Module):
    """observation (…, n) → (action (…, 12 or 24) in [−1, 1], action_si = action × scale), by the actor's network."""

    def __init__(self, actor: LoadedActor):
        super().__init__()
        self.actor = actor.module
        self.register_buffer("action_scale", torch.as_tensor(action_scale(actor.config.env), dtype=torch.float32))

    def forward(self, observation: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        action = self.actor(observation)
        return action, action * self.action_scale


def action_scale(env_cfg) -> np.ndarray:
    """(12,) or (24,): what the env multiplies an action by (`CyberDogEnv.step`): m per unit for a foot shift (x,
    y, z per leg), N·m per unit for a torque (foot_torque: the shifts, then the torques)."""
    torque = np.full(12, float(env_cfg.action_scale))
    if env_cfg.action_mode not in FOOT_MODES:
        return torque
    z = env_cfg.foot_offset_scale if env_cfg.foot_offset_scale_z is None else env_cfg.foot_offset_scale_z
    foot = np.tile([env_cfg.foot_offset_scale, env_cfg.foot_offset_scale, z], 4)
    return foot if env_cfg.action_mode == "foot" else np.concatenate([foot, torque])


def action_layout(env_cfg) -> list[dict]:
    """The action's entries: index, leg, name, unit, scale (× the action = `action_si`)."""
    scale = action_scale(env_cfg).tolist()
    shifts = [{"name": f"{leg}_{axis}", "joint": None, "unit": "m"}
              for leg in LEG_NAMES for axis in ("dx", "dy", "dz")]
    torques = [{"name": joint, "joint": joint, "unit": "N·m"} for joint in JOINTS]
    entries = (shifts if env_cfg.action_mode == "foot" else shifts + torques if env_cfg.action_mode == "foot_torque"
               else torques)
    return [{"index": i, "leg": LEG_NAMES[(i % 12) // 3], **e, "scale": scale[i]} for i, e in enumerate(entries)]


def observation_groups(actor: LoadedActor) -> list[dict]:
    """The observation's groups: name, slice [start, stop), unit, entry names, bounds the env clips to, and the
    scale the graph divides by (the typical magnitude; inf: hidden from this actor, its input is 0)."""
    cfg = actor.config.env
    scale = actor.module.observation_scale.numpy()
    groups, start = [], 0
    for name, size, low, high, _ in observation_layout(cfg):
        parts = (OBSERVATION_ENTRIES.get(name) or (JOINTS if size == 12 and name.startswith("joint_") else None)
                 or ([a["name"] for a in action_layout(cfg)] if name == "last_action" else None)
                 or ([] if size == 1 else [str(i) for i in range(size)]))
        entries = [f"{name}.{p}" for p in parts] if parts else [name]
        seen = bool(np.isfinite(scale[start:start + size]).all())
        groups.append({"name": name, "slice": [start, start + size], "unit": OBSERVATION_UNITS[name],
                       "entries": entries, "low": float(low), "high": float(high),
                       "scale": [float(s) if np.isfinite(s) else "inf" for s in scale[start:start + size]],
                       "seen_by_actor": seen,
                       **({"note": OBSERVATION_NOTES[name]} if name in OBSERVATION_NOTES else {})})
        start += size
    return groups


def recorded_observations(actor: LoadedActor, steps: int = PARITY_STEPS, speed: float = 1.0,
                          seed: int = 0) -> np.ndarray:
    """(k, n) float32: the observations the actor saw walking `steps` agent steps at `speed` (m/s) in the env it
    was trained in, deterministically from a stand (fewer where it fell)."""
    cfg = dataclasses.replace(actor.config.env, target_speed_range=(), prior_weight=0.0, prior_decay_steps=0,
                              trot_reference=False)
    env = CyberDogEnv(config=cfg, reward="stage2")
    try:
        obs, _ = env.reset(seed=seed, options={"target_speed": float(speed)})
        seen = [obs]
        for _ in range(steps - 1):
            obs, _, terminated, _, _ = env.step(actor(obs))
            seen.append(obs)
            if terminated:
                break
    finally:
        env.close()
    return np.array(seen, dtype=np.float32)


def _quiet_export():
    """The exporter's notices about optional packages it does not use (torchvision), and its deprecations, kept off
    the console while it runs; returns the logger levels to restore."""
    logger = logging.getLogger("torch.onnx")
    level = logger.level
    logger.setLevel(logging.ERROR)
    return logger, level


def export_onnx(module: ExportedActor, example: torch.Tensor, path: Path) -> Path:
    """`module` as ONNX at `path` (the dynamo exporter, opset ONNX_OPSET, dynamic batch, one file)."""
    onnx, _ = require_onnx()
    logger, level = _quiet_export()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", (FutureWarning, DeprecationWarning, UserWarning))
            torch.onnx.export(module, (example,), str(path), input_names=["observation"],
                              output_names=["action", "action_si"], opset_version=ONNX_OPSET, dynamo=True,
                              external_data=False, verbose=False,
                              dynamic_shapes={"observation": {0: torch.export.Dim("batch")}})
    finally:
        logger.setLevel(level)
    onnx.checker.check_model(str(path))
    return path


def export_torchscript(module: ExportedActor, example: torch.Tensor, path: Path) -> Path:
    """`module` traced to TorchScript at `path` (any batch shape: the network has no data-dependent branch)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", (FutureWarning, DeprecationWarning))
        traced = torch.jit.trace(module, (example,), check_trace=False)
        traced.save(str(path))
    return path


def parity(actor: LoadedActor, torchscript_file: Path, onnx_file: Path, observations: np.ndarray) -> dict:
    """The largest |difference| of each exported graph's outputs from the PyTorch actor's (× the scale for
    action_si) on `observations` (k, n)."""
    _, ort = require_onnx()
    reference = np.array([actor(o) for o in observations])
    reference_si = reference * action_scale(actor.config.env)
    scripted = torch.jit.load(str(torchscript_file))
    with torch.no_grad():
        ts_action, ts_si = (t.numpy() for t in scripted(torch.as_tensor(observations)))
    session = ort.InferenceSession(str(onnx_file), providers=["CPUExecutionProvider"])
    onnx_action, onnx_si = session.run(["action", "action_si"], {"observation": observations})
    diff = {"torchscript_action": ts_action - reference, "torchscript_action_si": ts_si - reference_si,
            "onnx_action": onnx_action - reference, "onnx_action_si": onnx_si - reference_si}
    return {"observations": len(observations), **{k: float(np.abs(v).max()) for k, v in diff.items()}}


def _sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def policy_sidecar(actor: LoadedActor, actor_file: Path, files: dict[str, Path], checked: dict) -> dict:
    """The sidecar: what goes in and out of the graphs, the control period, the walk a foot or residual policy
    needs, the source actor file (relative to the repository) and the parity check."""
    cfg = actor.config.env
    walk = cfg.walk
    n = sum(size for _, size, *_ in observation_layout(cfg))
    return {
        "format": FORMAT, "version": 1,
        "source_actor": portable_path(actor_file), "source_sha256": _sha256(actor_file), "source_meta": actor.meta,
        "files": {k: Path(v).name for k, v in files.items()},
        "graphs": {"torchscript": "torch.jit.trace of ExportedActor (cyberdog/rl/policy_export.py)",
                   "onnx": f"torch.onnx.export(dynamo=True), opset {ONNX_OPSET}, batch dimension dynamic"},
        "control_period_s": cfg.control_dt,
        "observation": {"name": "observation", "shape": ["batch", n], "dtype": "float32",
                        "applied_by_graph": "observation / scale (entrywise; an inf scale hides the entry), then "
                                            f"the MLP (ReLU hidden layers {list(actor.config.agent.hidden_sizes)}), "
                                            "then tanh",
                        "before_the_graph": "the env clips each entry to [low, high]; the graph does not clip",
                        "groups": observation_groups(actor)},
        "action": {"mode": cfg.action_mode,
                   "outputs": {"action": ["batch", cfg.action_size], "action_si": ["batch", cfg.action_size]},
                   "range": [-1.0, 1.0], "action_si": "action × scale, in each entry's unit",
                   "applied_as": ACTION_USE[cfg.action_mode], "layout": action_layout(cfg)},
        "walk": {"controller_dt_s": walk.sim.controller_dt, "gait": dataclasses.asdict(walk.gait),
                 "trot_controller": dataclasses.asdict(walk.controller), "pid": dataclasses.asdict(walk.pid),
                 "used": cfg.action_mode != "torque"},
        "parity": checked,
    }


def export_policy(actor_file: str | Path, out_dir: str | Path, stem: str = "policy", speed: float = 1.0,
                  steps: int = PARITY_STEPS, seed: int = 0) -> dict[str, Path]:
    """Write `<stem>_torchscript.pt`, `<stem>.onnx` and `<stem>.json` (the sidecar) for the actor file in `out_dir`,
    each graph checked against the PyTorch actor on a rollout of `steps` agent steps at `speed` m/s (`parity`).
    Returns {"torchscript", "onnx", "sidecar"} -> path."""
    require_onnx()  # before any work: the extra is missing, or it is not
    actor_file, out = Path(actor_file), Path(out_dir)
    actor = load_actor(actor_file)
    observations = recorded_observations(actor, steps, speed, seed)
    module = ExportedActor(actor).eval()
    example = torch.as_tensor(observations[:2])
    out.mkdir(parents=True, exist_ok=True)
    files = {"torchscript": export_torchscript(module, example, out / f"{stem}_torchscript.pt"),
             "onnx": export_onnx(module, example, out / f"{stem}.onnx")}
    checked = {**parity(actor, files["torchscript"], files["onnx"], observations), "rollout_speed_mps": speed,
               "rollout_seed": seed, "what": "max |exported − PyTorch| over the observations of a rollout in the env"}
    sidecar = out / f"{stem}.json"
    sidecar.write_text(json.dumps(policy_sidecar(actor, actor_file, files, checked), indent=1) + "\n")
    return {**files, "sidecar": sidecar}


__all__ = ["ExportDependencyError", "ExportedActor", "FORMAT", "ONNX_OPSET", "PARITY_STEPS", "action_layout",
           "action_scale", "export_onnx", "export_policy", "export_torchscript", "observation_groups", "parity",
           "policy_sidecar", "recorded_observations", "require_onnx"]
