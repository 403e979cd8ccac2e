# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The Gymnasium environment: API conformance and the model it wraps."""
import gymnasium
from gymnasium.utils.env_checker import check_env
from ipomdp_gaze.model.belief import bayes_update, uniform_log_belief
from ipomdp_gaze.model.fpoc import dprime_matrix, make_fpoc
from ipomdp_gaze.model.observation import gaussian_log_likelihood_ratio as llr
import ipomdp_gaze.simulation.gym  # noqa: F401  (registers the environment)
from ipomdp_gaze.simulation.gym import ENV_ID, VisualSearchEnv
import numpy as np
import pytest


@pytest.mark.filterwarnings('ignore:.*Box observation space m.* value is:UserWarning')
@pytest.mark.parametrize('kwargs', [{}, {'observe': 'evidence'},
                                    {'reward': 'fixate_target', 'fpoc': 'camera', 'rows': 5,
                                     'cols': 6}])
def test_passes_the_gymnasium_checker(kwargs):
    env = gymnasium.make(ENV_ID, **kwargs).unwrapped
    check_env(env, skip_render_check=True)


@pytest.mark.filterwarnings('ignore:.*Box observation space m.* value is:UserWarning')
@pytest.mark.parametrize('kwargs', [
    {'motion_sigma_cells': 0.7, 'jump_prob': 0.05},
    {'absent_prior': 0.4, 'absent_rate': 0.3},
    {'absent_prior': 0.5, 'absent_rate': 0.5, 'motion_sigma_cells': 0.5, 'observe': 'evidence',
     'fpoc': 'camera', 'rows': 5, 'cols': 6}])
def test_moving_and_absent_targets_pass_the_gymnasium_checker(kwargs):
    env = gymnasium.make(ENV_ID, **kwargs).unwrapped
    check_env(env, skip_render_check=True)


def test_empty_scene_terminates_absent_and_the_reward_counts_every_hypothesis():
    env = VisualSearchEnv(rows=3, cols=3, fpoc='camera', fpoc_params={'dprime': 3.0},
                          absent_prior=0.5, confidence=0.99)
    obs, info = env.reset(seed=2, options={'present': False})
    assert obs['absent'][0] == pytest.approx(0.5) and info['present'] is False
    assert info['target'] is None                       # no target to name (it was a cell)
    assert obs['belief'].sum() == pytest.approx(0.5)
    for _ in range(30):
        obs, reward, terminated, truncated, info = env.step(4)
        assert info['target'] is None
        full = np.append(env.belief, env.absent_probability)
        assert reward == pytest.approx(np.sum(full * np.log(full)))
        assert obs['belief'].sum() + obs['absent'][0] == pytest.approx(1.0)
        if terminated:
            break
    assert terminated and info['decision'] == 'absent' and info['absent_probability'] >= 0.99


def test_absent_rate_draws_empty_scenes_from_the_env_generator():
    env = VisualSearchEnv(absent_prior=0.5, absent_rate=0.5)
    present = [env.reset(seed=s)[1]['present'] for s in range(200)]
    assert 60 < sum(present) < 140
    infos = [env.reset(seed=s)[1] for s in range(200)]
    assert all((i['target'] is None) is (not i['present']) for i in infos)
    assert [env.reset(seed=s)[1]['present'] for s in range(200)] == present


def test_moving_target_walks_and_the_belief_is_predicted():
    from ipomdp_gaze.model.motion import Motion
    env = VisualSearchEnv(rows=5, cols=5, motion_sigma_cells=1.0, confidence=0.5, max_steps=40)
    env.reset(seed=4, options={'target': 12})
    d = dprime_matrix(env.grid, env.fpoc)
    motion = Motion(env.grid, 1.0)
    log_b = np.log(np.full(25, 1 / 25))
    targets = []
    for t in range(40):
        obs, _, terminated, truncated, info = env.step(t % 25)
        log_b = bayes_update(log_b, llr(env._evidence, d[:, t % 25]))
        np.testing.assert_allclose(info['map_probability'], np.exp(log_b).max(), rtol=1e-9)
        motion.predict_log(log_b)
        np.testing.assert_allclose(obs['belief'].ravel(), np.exp(log_b), rtol=1e-9)
        targets.append(info['target'])
        assert not terminated                   # a tracker runs to max_steps
    assert truncated and len(set(targets)) > 3


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


@pytest.mark.parametrize('kwargs, words', [
    ({'motion_sigma_cells': -1.0}, 'sigma_cells must be finite and >= 0'),
    ({'jump_prob': 1.0}, r'jump_prob must be a probability in \[0, 1\)'),
    ({'absent_prior': 1.2}, r'absent.prior must be a probability in \[0, 1\)'),
    ({'confidence': 1.0}, r'confidence must be between 0 and 1 \(exclusive\)'),
    ({'absent_rate': -0.1}, r'absent_rate must be a probability in \[0, 1\)'),
])
def test_bad_motion_and_absent_options_are_named(kwargs, words):
    with pytest.raises(ValueError, match=words):
        VisualSearchEnv(**kwargs)


@pytest.mark.parametrize('options, words', [
    ({'target': 99}, r"options\['target'\] must be a cell index in \[0, 25\), got 99"),
    ({'target': -1}, r'got -1'),
    ({'target': 2.5}, r'got 2.5'),
    ({'present': False}, r'needs absent_prior > 0'),
    ({'present': 'no'}, r"options\['present'\] must be True or False"),
    ({'targte': 3}, r"unknown reset option\(s\) 'targte'; valid: present, target"),
])
def test_bad_reset_options_are_named_before_the_episode(options, words):
    env = VisualSearchEnv(rows=5, cols=5)
    with pytest.raises(ValueError, match=words):
        env.reset(seed=0, options=options)


def test_a_truncated_episode_needs_a_reset_as_a_terminated_one():
    env = VisualSearchEnv(rows=5, cols=5, max_steps=2, confidence=0.999999)
    env.reset(seed=0, options={'target': 3})
    truncated = [env.step(0)[3] for _ in range(2)]
    assert truncated == [False, True]
    with pytest.raises(gymnasium.error.ResetNeeded, match='terminated or truncated'):
        env.step(0)
    env.reset(seed=1)
    env.step(0)


def test_max_steps_below_one_is_refused():
    with pytest.raises(ValueError, match='max_steps must be at least 1, got 0'):
        VisualSearchEnv(rows=5, cols=5, max_steps=0)


@pytest.mark.parametrize('kwargs, words', [
    ({'max_steps': 2.5}, 'max_steps must be a non-negative integer, got 2.5'),
    ({'max_steps': '10'}, "max_steps must be a non-negative integer, got '10'"),
    ({'max_steps': True}, 'max_steps must be a non-negative integer, got True'),
    ({'max_steps': float('inf')}, 'max_steps must be a non-negative integer, got inf'),
    ({'start_cell': 2.5}, 'start_cell must be a non-negative integer'),
    ({'start_cell': True}, 'start_cell must be a non-negative integer'),
    ({'scan': 'yes'}, 'scan must be True or False'),
])
def test_integer_arguments_are_refused_not_truncated(kwargs, words):
    """QA: max_steps=2.5 ran 2 steps, start_cell=True started at cell 1."""
    with pytest.raises(ValueError, match=words):
        VisualSearchEnv(rows=5, cols=5, **kwargs)


@pytest.mark.parametrize('action', [2.7, '3', True, np.float64(1.0), None])
def test_an_action_outside_the_space_is_refused(action):
    """QA: step(2.7) fixated cell 2 although Discrete(N).contains(2.7) is False."""
    env = VisualSearchEnv(rows=5, cols=5)
    env.reset(seed=0)
    with pytest.raises(ValueError, match='action must be a cell index'):
        env.step(action)
    assert env.step(np.int64(3))[4]['steps'] == 1          # a numpy integer is an index


@pytest.mark.parametrize('kwargs', [{'fpoc': 'camera'}, {'spacing_deg': 5.0},
                                    {'fpoc_params': {'dprime': 2.0}}])
def test_fpoc_and_spacing_cannot_go_with_an_observation_model(kwargs):
    """QA: they were ignored silently beside observation=."""
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.observation import GaussianObservation
    grid = Grid(3, 3)
    with pytest.raises(ValueError, match='cannot go with observation='):
        VisualSearchEnv(observation=GaussianObservation(grid, make_fpoc('human')), **kwargs)


def test_a_count_model_with_scan_tables_starts_from_the_scanned_belief():
    """QA: the env started from the uniform prior where simulate, training and find scan."""
    from gymnasium.utils.seeding import np_random
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.observation import CountObservation
    from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings
    grid = Grid(3, 3)
    rng = np.random.default_rng(0)
    model = CountObservation(grid, rng.dirichlet(np.ones(3), size=(3, 3)),
                             rng.dirichlet(np.ones(3), size=(3, 3)),
                             scan_target=np.array([0.1, 0.3, 0.6]),
                             scan_null=np.array([0.7, 0.2, 0.1]))
    env = VisualSearchEnv(observation=model)
    obs, info = env.reset(seed=5, options={'target': 4})
    # The scan is the reset's first draw from np_random (the target was given).
    counts = model.sample_scan(4, np_random(5)[0], present=True)
    session = SearchSession(grid, model, None, SearchSettings(confidence=0.95))
    session.reset()
    session.scan(Frame(counts, kind='scan'))
    np.testing.assert_allclose(obs['belief'].ravel(), session.belief, rtol=1e-12)
    assert info['entropy'] < np.log(9) - 1e-6
    evidence = VisualSearchEnv(observation=model, observe='evidence')
    obs, _ = evidence.reset(seed=5, options={'target': 4})
    np.testing.assert_array_equal(obs['evidence'].ravel(), counts)     # the scan's counts
    plain = VisualSearchEnv(observation=model, scan=False)
    obs, info = plain.reset(seed=5, options={'target': 4})
    np.testing.assert_allclose(obs['belief'].ravel(), np.full(9, 1 / 9))


def test_a_step_before_the_first_reset_asks_for_a_reset():
    """QA: the raw env raised the session's OrderError, not Gymnasium's ResetNeeded."""
    env = VisualSearchEnv(rows=5, cols=5)
    with pytest.raises(gymnasium.error.ResetNeeded, match='reset'):
        env.step(0)
    env.reset(seed=0)
    env.step(0)


@pytest.mark.filterwarnings('ignore:.*Box observation space m.* value is:UserWarning')
def test_a_prior_is_where_targets_are_drawn_and_the_belief_starts():
    """QA (an RL researcher): a centre-biased task in the environment, as in evaluate --prior."""
    prior = np.zeros((4, 4))
    prior[1, 1], prior[2, 3] = 0.25, 0.75
    env = VisualSearchEnv(rows=4, cols=4, observe='evidence', prior=prior, confidence=1 - 1e-9)
    check_env(env, skip_render_check=True)
    targets = [env.reset(seed=s)[1]['target'] for s in range(40)]
    assert set(targets) == {5, 11}
    assert 0.5 < targets.count(11) / 40 < 0.95         # 0.75 of 40: sd 0.07
    obs, info = env.reset(seed=2)
    np.testing.assert_allclose(env.belief, prior.ravel())
    d = dprime_matrix(env.grid, env.fpoc)
    with np.errstate(divide='ignore'):
        log_b = np.log(prior.ravel())
    for action in (0, 6):
        obs, reward, *_ = env.step(action)
        log_b = bayes_update(log_b, llr(obs['evidence'].ravel(), d[:, action]))
        b = np.exp(log_b)
        np.testing.assert_allclose(env.belief, b, atol=1e-12)
        assert reward == pytest.approx(np.sum(b[b > 0] * np.log(b[b > 0])))
    assert env.reset(options={'target': 5})[1]['target'] == 5
    with pytest.raises(ValueError, match=r"options\['target'\] 0 is a cell the prior rules out"):
        env.reset(options={'target': 0})
    with pytest.raises(ValueError, match='prior must sum to 1'):
        VisualSearchEnv(rows=4, cols=4, prior=np.ones((4, 4)))


def test_an_fpoc_whose_frames_overflow_is_refused_as_simulate_refuses_it():
    """QA: d' 1e200 made every frame a refused one: the belief never moved, steps went on."""
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.observation import GaussianObservation
    with pytest.raises(ValueError, match=r"d' up to 1e\+150 can be simulated, the FPOC gives "
                                         r'1e\+200'):
        VisualSearchEnv(rows=3, cols=3, fpoc='camera', fpoc_params={'dprime': 1e200})
    with pytest.raises(ValueError, match='can be simulated'):
        VisualSearchEnv(observation=GaussianObservation(Grid(3, 3),
                                                        make_fpoc('camera', dprime=1e155)))


def test_a_frame_the_search_refuses_is_an_error_not_a_step():
    """A model of one's own whose frame the search refuses: the step says so (it was silent)."""
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.model.observation import GaussianObservation

    class Broken(GaussianObservation):

        def sample(self, targets, fixations, rng, present=None):
            frame = super().sample(targets, fixations, rng, present)
            frame[0] = np.inf
            return frame

    env = VisualSearchEnv(observation=Broken(Grid(3, 3), make_fpoc('camera')))
    env.reset(seed=0)
    with pytest.raises(RuntimeError, match='drew a frame the search refused: evidence contains '
                                           r'\+/-inf'):
        env.step(4)
    np.testing.assert_allclose(env.belief, np.full(9, 1 / 9))


@pytest.mark.parametrize('kwargs, words', [
    ({'observation': 5}, 'observation must be an observation model with its grid, an '
                         'observation file or a shipped model name, got int'),
    ({'observation': make_fpoc('camera')}, r'got CameraFPOC \(an FPOC goes in fpoc=\)'),
    ({'fpoc_params': [1, 2]}, 'fpoc_params must be a dict of parameter names and values, got '
                              'list'),
    ({'fpoc': make_fpoc('camera'), 'fpoc_params': {'dprime': 9.0}},
     'fpoc_params cannot go with an FPOC object'),
])
def test_an_observation_or_fpoc_params_of_the_wrong_kind_is_named(kwargs, words):
    """QA: observation=5 was AttributeError 'int' ... 'grid'; an FPOC's fpoc_params were lost."""
    with pytest.raises(ValueError, match=words):
        VisualSearchEnv(**kwargs)
