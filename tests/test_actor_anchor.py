"""A continuation from an actor alone: `--init-from` an actor file (new critics; widened for an input it did not
observe, `observe_pd_stiffness`) and the pull toward the actor a stage started from (StageConfig.actor_anchor),
which survives a checkpoint and a resume."""
import pytest
import torch
from tensordict import TensorDict

from conftest import tiny
from rl_helpers import batch as _batch
from cyberdog import config as C
from cyberdog.rl.checkpoint import load_checkpoint, load_torch_file
from cyberdog.rl.td3 import TD3, UpdateSettings
from cyberdog.rl.trainer import Trainer


def _anchored(agent: TD3, weight: float) -> UpdateSettings:
    """A stage that pulls toward the actor it starts from with `weight`, begun now."""
    settings = UpdateSettings.of(agent.cfg, C.StageConfig(actor_anchor=weight))
    agent.begin_stage(settings)
    return settings


def _actions(agent: TD3, obs: torch.Tensor) -> torch.Tensor:
    with torch.no_grad():
        return agent.actor(TensorDict({"observation": obs}, [obs.shape[0]]))["action"]


def test_the_anchor_term_is_the_distance_to_the_frozen_actor():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16,), action_l2=0.0), 50, 12)
    b = _batch(8)
    start = _actions(agent, b["observation"])
    anchored = _anchored(agent, 3.0)
    with torch.no_grad():  # the actor moves on; the anchor does not
        for p in agent.actor_net.parameters():
            p.add_(0.05 * torch.randn_like(p))
    now = _actions(agent, b["observation"])
    assert not torch.allclose(now, start)
    with torch.no_grad():
        pulled = agent.actor_loss(b, anchored) - agent.actor_loss(b, UpdateSettings.of(agent.cfg))
    assert float(pulled) == pytest.approx(3.0 * float(((now - start) ** 2).mean()), rel=1e-5)


@pytest.mark.parametrize("anchor", [0.0, 1000.0])
def test_a_strong_anchor_holds_the_actor_where_it_started(anchor):
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(32, 32), policy_delay=1, actor_lr=3e-3, action_l2=0.0), 50, 12)
    b = _batch(32)
    start = _actions(agent, b["observation"])
    settings = _anchored(agent, anchor)
    for _ in range(200):
        agent.update(b, settings)
    moved = float((_actions(agent, b["observation"]) - start).abs().mean())
    assert (moved < 0.02) if anchor else (moved > 0.1)


def test_the_anchor_is_saved_with_the_agent_and_restored():
    torch.manual_seed(0)
    agent = TD3(C.AgentConfig(hidden_sizes=(16,)), 50, 12)
    _anchored(agent, 1.0)
    frozen = {k: v.clone() for k, v in agent.anchor.named().items()}
    with torch.no_grad():
        for p in agent.actor_net.parameters():
            p.add_(1.0)
    other = TD3(C.AgentConfig(hidden_sizes=(16,)), 50, 12)
    other.load_state_dict(agent.state_dict())
    assert other.anchor is not None
    assert all(torch.equal(v, frozen[k]) for k, v in other.anchor.named().items())
    assert TD3(C.AgentConfig(hidden_sizes=(16,)), 50, 12).anchor is None  # none until a stage asks for one


def test_a_stage_from_an_actor_file_is_pulled_toward_that_actor(tmp_path):
    cfg = tiny("train.learning_starts=0", "train.stage1.max_env_steps=200", "train.batch_size=32")
    Trainer(cfg, tmp_path / "a", stages=(1,), progress=False).run()
    actor_file = tmp_path / "a" / "stage1_final_actor.pt"
    start = load_torch_file(actor_file, "actor")["actor"]
    # its actor (and the target actor) start from the file, the critics anew, no uniform random start
    random_start = C.override(cfg, ["train.stage2.max_env_steps=200", "train.init_random_frames=100"])
    fresh = Trainer(random_start, tmp_path / "fresh", stages=(2,), init_from=actor_file, progress=False)
    try:
        mine = fresh.agent.network_state()
        for k, v in start.items():
            assert torch.equal(mine["actor_network_params." + k], v)
            assert torch.equal(mine["target_actor_network_params." + k], v)
        trained = load_checkpoint(tmp_path / "a" / "stage1_final.pt")["agent"]["loss"]
        critics = [k for k in trained if k.startswith("qvalue_network_params.") and k.endswith("weight")]
        assert critics and not any(torch.equal(mine[k], trained[k]) for k in critics)  # stage 1 trained its own
        assert fresh.agent.updates == 0 and fresh._random_frames_left(2) == 0
    finally:
        fresh.close()
    cont = C.override(cfg, ["train.stage2.max_env_steps=200", "train.stage2.actor_anchor=5.0"])
    t = Trainer(cont, tmp_path / "b", stages=(2,), init_from=actor_file, progress=False)
    assert not t.agent.load_actor(start) and t.agent.actor_from_file  # the same inputs: nothing widened
    t.run()
    anchor = t.agent.anchor.named()
    assert t.agent.actor_updates > 0
    assert all(torch.equal(anchor[k], v) for k, v in start.items())  # the actor the stage started from
    moved = t.agent.actor_net.named()
    assert any(not torch.equal(moved[k], v) for k, v in start.items())  # while the actor itself learned
    with pytest.raises(ValueError, match="actor_anchor"):
        C.StageConfig(actor_anchor=-1.0)


def test_an_observed_stiffness_is_the_drivers_kp_over_the_default():
    from cyberdog.envs.cyberdog_env import CyberDogEnv, observation_size

    base = C.EnvConfig(action_mode="foot", observe_last_action=True)
    stiff = C.EnvConfig(action_mode="foot", observe_last_action=True, observe_pd_stiffness=True)
    assert observation_size(base) == 62 and observation_size(stiff) == 63
    for scale in (1.0, 1.4):
        walk = C.WalkConfig()
        cfg = C.EnvConfig(action_mode="foot", observe_last_action=True, observe_pd_stiffness=True,
                          walk=C.WalkConfig(**{**walk.__dict__, "pid": walk.pid.stiffness_scaled(scale)}))
        env = CyberDogEnv(config=cfg, reward="stage1")
        try:
            obs, _ = env.reset(seed=0)
            assert obs.shape == (63,) and obs[-1] == pytest.approx(scale, rel=1e-6)
            obs, *_ = env.step(torch.zeros(12).numpy())
            assert obs[-1] == pytest.approx(scale, rel=1e-6)
        finally:
            env.close()


def test_an_actor_of_fewer_inputs_is_widened_and_acts_as_before():
    torch.manual_seed(0)
    narrow = TD3(C.AgentConfig(hidden_sizes=(16,)), 62, 12)
    wide = TD3(C.AgentConfig(hidden_sizes=(16,)), 63, 12)
    assert wide.load_actor(narrow.actor.state_dict()) == 16 + 1  # a column of 16 weights, one input scale
    obs = torch.randn(6, 62)
    for extra in (0.0, 1.4, 3.0):  # the new input does not change the action until training uses it
        widened = torch.cat([obs, torch.full((6, 1), extra)], 1)
        assert torch.allclose(_actions(wide, widened), _actions(narrow, obs), atol=1e-6)
    with pytest.raises(ValueError, match="has shape"):  # another hidden size is not widened
        TD3(C.AgentConfig(hidden_sizes=(32,)), 63, 12).load_actor(narrow.actor.state_dict())


def test_fresh_critics_start_a_stage_from_a_final_agent_as_from_its_actor_file(tmp_path):
    cfg = tiny("train.learning_starts=0", "train.stage1.max_env_steps=200", "train.batch_size=32")
    Trainer(cfg, tmp_path / "a", stages=(1,), progress=False).run()
    final = tmp_path / "a" / "stage1_final.pt"
    trained = load_checkpoint(final)["agent"]
    cont = C.override(cfg, ["train.stage2.max_env_steps=200"])
    kept = Trainer(cont, tmp_path / "kept", stages=(2,), init_from=final, progress=False)
    fresh = Trainer(C.override(cont, ["train.stage2.fresh_critics=true"]), tmp_path / "fresh", stages=(2,),
                    init_from=final, progress=False)
    actor_only = Trainer(cont, tmp_path / "file", stages=(2,), init_from=tmp_path / "a" / "stage1_final_actor.pt",
                         progress=False)
    try:
        critics = [k for k in trained["loss"] if k.startswith("qvalue_network_params.") and k.endswith("weight")]
        actor = [k for k in trained["loss"] if k.startswith("actor_network_params.")]
        assert critics and actor
        k_state, f_state, a_state = (t.agent.network_state() for t in (kept, fresh, actor_only))
        assert all(torch.equal(k_state[k], trained["loss"][k]) for k in critics)  # by default the critics carry over
        assert not any(torch.equal(f_state[k], trained["loss"][k]) for k in critics)  # fresh_critics: new ones
        assert all(torch.equal(f_state[k], trained["loss"][k]) for k in actor)  # and the same actor
        assert all(torch.equal(f_state[k], a_state[k]) for k in f_state)  # exactly as from the actor file
        assert kept.agent.updates > 0 and fresh.agent.updates == 0 and fresh.agent.actor_from_file
    finally:
        for t in (kept, fresh, actor_only):
            t.close()
