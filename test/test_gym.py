# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The Gymnasium environment: API conformance and the model it wraps."""
import gymnasium
from gymnasium.utils.env_checker import check_env
from ipomdp_gaze.belief import bayes_update, uniform_log_belief
from ipomdp_gaze.fpoc import dprime_matrix
import ipomdp_gaze.gym  # noqa: F401  (registers the environment)
from ipomdp_gaze.gym import ENV_ID, VisualSearchEnv
from ipomdp_gaze.observation import gaussian_log_likelihood_ratio as llr
import numpy as np
import pytest


@pytest.mark.filterwarnings('ignore:.*Box observation space m.* value is:UserWarning')
@pytest.mark.parametrize('kwargs', [{}, {'observe': 'evidence'},
                                    {'reward': 'fixate_target', 'fpoc': 'camera', 'rows': 5,
                                     'cols': 6}])
def test_passes_the_gymnasium_checker(kwargs):
    env = gymnasium.make(ENV_ID, **kwargs).unwrapped
    check_env(env, skip_render_check=True)


def test_belief_follows_the_bayes_update_and_reward_is_negative_entropy():
    env = VisualSearchEnv(rows=4, cols=4, observe='evidence')
    obs, info = env.reset(seed=5)
    d = dprime_matrix(env.grid, env.fpoc)
    log_b = uniform_log_belief(16)
    for action in (0, 5, 15):
        obs, reward, *_ = env.step(action)
        log_b = bayes_update(log_b, llr(obs['evidence'].ravel(), d[:, action]))
        b = np.exp(log_b)
        np.testing.assert_allclose(env.belief, b, atol=1e-12)
        assert reward == pytest.approx(np.sum(b * np.log(b)))
        assert obs['fixation'] == action


def test_seeded_reset_reproduces_and_target_is_in_info():
    env = VisualSearchEnv()
    a = [env.reset(seed=3)[1]['target']] + [env.step(24)[1] for _ in range(3)]
    b = [env.reset(seed=3)[1]['target']] + [env.step(24)[1] for _ in range(3)]
    assert a == b
    assert env.reset(seed=3, options={'target': 7})[1]['target'] == 7


def test_terminates_at_confidence_and_truncates_at_step_limit():
    env = VisualSearchEnv(fpoc='camera', fpoc_params={'dprime': 6.0}, confidence=0.99)
    env.reset(seed=0, options={'target': 24})
    terminated = False
    for _ in range(10):
        _, _, terminated, truncated, info = env.step(24)
        if terminated:
            break
    assert terminated and info['map_cell'] == 24
    env = VisualSearchEnv(max_steps=2, fpoc='human', fpoc_params={'foveal_dprime': 0.01})
    env.reset(seed=0)
    assert env.step(0)[3] is False and env.step(0)[3] is True


def test_render_modes():
    env = VisualSearchEnv(rows=3, cols=4, render_mode='rgb_array')
    env.reset(seed=0)
    env.step(5)
    image = env.render()
    assert image.dtype == np.uint8 and image.shape == (48, 64, 3)
    text = VisualSearchEnv(rows=3, cols=4, render_mode='ansi')
    text.reset(seed=0)
    text.step(5)
    assert text.render().count('\n') == 3 and '[' in text.render()


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match='valid rewards'):
        VisualSearchEnv(reward='saliency')
    with pytest.raises(ValueError, match='action must be a cell index'):
        env = VisualSearchEnv()
        env.reset(seed=0)
        env.step(49)


def test_example_drives_the_env_with_a_shipped_kernel_and_baselines(capsys):
    """
    The example's searches end at 95% confidence, so each guess is right with p >= 0.95.

    Over 60 episodes, fewer than 80% right has probability below 1e-4 for a correct model.
    """
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / 'examples' / 'gym_search.py'
    spec = importlib.util.spec_from_file_location('gym_search_example', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    results = module.main(episodes=60, seed=1)
    assert len(results) == 3
    for mean_steps, right in results.values():
        assert right >= 0.8 and 1 <= mean_steps < 49
    assert 'shipped kernel' in capsys.readouterr().out
