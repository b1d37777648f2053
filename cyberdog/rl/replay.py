"""Replay buffer of transitions (`torchrl.data`), whose contents travel in checkpoints as plain tensors."""
from __future__ import annotations

from typing import Iterator

from tensordict import TensorDict, TensorDictBase
from torchrl.data import LazyTensorStorage, TensorDictReplayBuffer
from torchrl.data.replay_buffers.samplers import RandomSampler

# what one transition keeps: enough for the TD target (s, a, r, s', done), and the step's energy (J, Eq. 7) so
# that its reward can be recomputed for another energy weight (`relabel_rewards`)
TRANSITION_KEYS = ("observation", "action", ("next", "observation"), ("next", "reward"), ("next", "done"),
                   ("next", "terminated"), ("next", "energy_J"))

def make_replay_buffer(capacity: int) -> TensorDictReplayBuffer:
    """Uniform replay over the last `capacity` transitions (FIFO), sampled with torch's global RNG (each
    `sample` call names its batch size)."""
    return TensorDictReplayBuffer(storage=LazyTensorStorage(capacity), sampler=RandomSampler())

def relabel_rewards(rb: TensorDictReplayBuffer, delta_energy_weight: float, delta_per_step: float = 0.0) -> None:
    """Add `delta_energy_weight · energy_J + delta_per_step` to every stored reward, in place: the rewards
    become those of a reward whose energy weight E (Eq. 10) is larger by `delta_energy_weight` and whose
    constant per-step bonus (the keep-moving term D·Ts/Tf) is larger by `delta_per_step`."""
    n = len(rb)
    if n == 0 or (delta_energy_weight == 0 and delta_per_step == 0):
        return
    stored = rb[:n]
    reward = stored["next", "reward"]
    stored["next", "reward"] = reward + (delta_energy_weight * stored["next", "energy_J"].reshape(reward.shape)
                                         + delta_per_step)
    rb[:n] = stored


SAMPLE_CHUNK = 64  # batches drawn per replay-buffer call in `sample_batches` (bounds its memory)


def sample_batches(rb: TensorDictReplayBuffer, n: int, batch_size: int) -> Iterator[TensorDictBase]:
    """`n` independent uniform batches (with replacement) of `batch_size` transitions.

    The same distribution as `n` calls of `rb.sample()` while the buffer does not change, but drawn with one
    index draw and one gather per `SAMPLE_CHUNK` batches: the per-call overhead of the replay buffer (~0.4 ms,
    a few % of a TD3 update on a CPU) is paid once per chunk.
    """
    while n > 0:
        k = min(n, SAMPLE_CHUNK)
        yield from rb.sample(k * batch_size).split(batch_size)
        n -= k


TROT_ACTION_KEY = ("next", "trot_action")  # the trot controller's torque at the transition's s, in action units
#                                           (torque mode; kept only when the actor imitates it: AgentConfig)


def transitions(batch: TensorDictBase, extra_keys=()) -> TensorDictBase:
    """The keys a transition keeps (and `extra_keys`), flattened to one batch dimension."""
    return batch.select(*TRANSITION_KEYS, *extra_keys).reshape(-1)

def buffer_state(rb: TensorDictReplayBuffer) -> dict:
    """Contents (in storage order) and write cursor (the slot the next transition goes to), as a plain dict of
    tensors. The buffer is written only by `extend` since it was last emptied, one slot after the other (FIFO),
    so the cursor is the count of transitions written, modulo the capacity.
    Not TorchRL's `rb.state_dict()`: it round-trips too, but holds the whole preallocated storage, every one of the
    `buffer_size` slots however few are filled (~0.56 GB at 10⁶ slots of 62 observations), in every checkpoint."""
    n, capacity = len(rb), int(rb.storage.max_size)
    data = rb[:n].to_dict() if n else {}
    return {"size": n, "cursor": rb.write_count % capacity if n else 0, "capacity": capacity, "data": data}

def load_buffer_state(rb: TensorDictReplayBuffer, state: dict, extra_keys=()) -> None:
    """Refill a buffer from `buffer_state`, slots and cursor as they were; raises ValueError if the capacities
    differ or a key the run keeps (`TRANSITION_KEYS` and `extra_keys`) is missing."""
    capacity = int(rb.storage.max_size)
    if int(state["capacity"]) != capacity:
        raise ValueError(f"replay buffer capacity in checkpoint ({state['capacity']}) differs from config "
                         f"(train.buffer_size={capacity})")
    rb.empty()
    n, cursor = int(state["size"]), int(state["cursor"]) % capacity
    if n == 0:
        return
    if cursor != n % capacity and n != capacity:
        raise ValueError(f"replay buffer in checkpoint holds {n} of {capacity} transitions with its cursor at "
                         f"{cursor}: a buffer not yet full is written up to its size")
    data = TensorDict(state["data"], batch_size=[n])
    missing = [k for k in (*TRANSITION_KEYS, *extra_keys) if k not in data.keys(include_nested=True)]
    if missing:
        raise ValueError(f"the stored transitions lack {missing} (a checkpoint of an older version); "
                         f"start a new run, or continue that one with the version that wrote it")
    rb.extend(data)  # writes slots 0..n-1 in order, as they were stored; the cursor is then at n (mod capacity)
    if cursor != n % capacity:  # a full buffer that had wrapped: the first `cursor` transitions written again, to
        rb.extend(data[:cursor])  # the same slots, move the cursor to where it stood
    if len(rb) != n:
        raise ValueError(f"replay buffer restored {len(rb)} transitions, checkpoint has {n}")

__all__ = ["make_replay_buffer", "sample_batches", "transitions", "buffer_state", "load_buffer_state",
           "TRANSITION_KEYS", "TROT_ACTION_KEY"]
