"""Reinforcement learning layer: networks, the TD3/DDPG update, agent, replay, checkpoints and the trainer.

Imports torch, torchrl and the environment layer; nothing below it imports this package.
"""
from cyberdog.rl.agent import Agent, NonFiniteError
from cyberdog.rl.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from cyberdog.rl.trainer import Trainer

__all__ = ["Agent", "NonFiniteError", "CheckpointError", "load_checkpoint", "save_checkpoint", "Trainer"]
