"""Reinforcement learning layer: networks, the TD3/DDPG agent and its update, replay, checkpoints and the trainer.

Imports torch, torchrl and the environment layer; nothing below it imports this package. Its modules import one
another by module (`from cyberdog.rl.td3 import TD3`), never through this package, and no two import each other.
"""
from cyberdog.rl.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from cyberdog.rl.td3 import TD3, NonFiniteError, UpdateSettings
from cyberdog.rl.trainer import Trainer

__all__ = ["TD3", "UpdateSettings", "NonFiniteError", "CheckpointError", "load_checkpoint", "save_checkpoint",
           "Trainer"]
