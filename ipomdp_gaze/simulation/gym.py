# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Gymnasium environment ``ipomdp_gaze/VisualSearch-v0``: the I-POMDP visual-search task.

Each step fixates one cell (``Discrete(N)`` action), draws one observation per cell from the
observation model (docs/design.md section 1) and updates the belief with the one Bayes step. The
observation is a ``Dict`` with the belief grid (or, with ``observe='evidence'``, the raw evidence
of the last frame) and the current fixation. The reward is the infomax reward ``sum_i B_i log B_i``
of the new belief (``reward='fixate_target'``: the belief at the fixated cell). An episode
terminates when the most likely cell reaches ``confidence`` (in (0, 1), as everywhere) and is
truncated after ``max_steps`` fixations; stepping on after either needs a reset. The
belief, the Bayes step and the stop rules are the search session's
(:mod:`ipomdp_gaze.search.session`,
with the agent choosing every fixation). The hidden target is in ``info['target']`` for oracle
baselines (``None`` in an empty scene: there is no target to name).

By default the observation model is the Gaussian model of ``fpoc`` on a ``rows x cols`` grid
(7x7); ``observation=`` takes any observation model instead, for example a count model or the
path or shipped name of an ``ipomdp_gaze/observation-v1`` file, and its grid. A model whose
drawn frames the search would refuse (a d' above 1e150) is refused when the environment is
made, as the simulator refuses it; a refused frame in a step is a RuntimeError.

Beyond the paper (docs/design.md section 7), with the defaults off: ``motion_sigma_cells`` and
``jump_prob`` make the target take a step of :class:`ipomdp_gaze.model.motion.Motion` after every
fixation (the belief is predicted with the same step, so the observation is the belief the next
fixation is chosen from; ``info`` describes the fixation just made, before the step); such an
episode never terminates early, it tracks until ``max_steps``. ``absent_prior`` gives the belief
the absent hypothesis: the observation gains ``'absent'`` (``P(absent)``, shape (1,)), the
``belief`` grid holds the cells (summing to ``1 - P(absent)``), the infomax reward is over all
N + 1 hypotheses, and an episode also terminates when ``P(absent)`` reaches ``confidence``.
``absent_rate`` is the fraction of episodes whose scene is empty (drawn at reset from
``np_random``; ``options={'present': False}`` forces one). ``prior`` ((N,) or (rows, cols),
summing to 1) is where the target is a priori: reset draws it from the prior and the belief
starts there (default uniform; ``options={'target': cell}`` must be a cell it allows).

A count model with scan tables (``faces-420`` and the other calibrated face models) starts each
episode with its one-time whole-image scan, drawn at reset (``scan=False``: from the prior),
as the simulation, training and ``find`` start (docs/design.md section 6.8): the first
observation is the scanned belief (``observe='evidence'``: the scan's counts).
"""
from __future__ import annotations

from pathlib import Path

import gymnasium
from gymnasium import spaces
from ipomdp_gaze.files.render import belief_heatmap, belief_text
from ipomdp_gaze.model.belief import draw_cells, map_cell
from ipomdp_gaze.model.checks import positive_int
from ipomdp_gaze.model.fpoc import FPOC, make_fpoc
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import check_probability
from ipomdp_gaze.model.observation import as_observation, GaussianObservation
from ipomdp_gaze.search.session import Frame, SearchSession, SearchSettings, session_view
import numpy as np

ENV_ID = 'ipomdp_gaze/VisualSearch-v0'
# What reset(options=...) takes: the target's cell, and whether it is there at all.
RESET_OPTIONS = frozenset({'target', 'present'})
REWARDS = ('infomax', 'fixate_target')
OBSERVE = ('belief', 'evidence')
# The grid's spacing when neither it nor an observation model says (the paper's 7x7 task).
DEFAULT_SPACING_DEG = 0.42


class VisualSearchEnv(gymnasium.Env):
    """Find a hidden target on a ``rows x cols`` grid by choosing fixations."""

    metadata = {'render_modes': ['rgb_array', 'ansi'], 'render_fps': 4}

    def __init__(self, rows: int | None = None, cols: int | None = None,
                 spacing_deg: float | None = None, fpoc: str | FPOC | None = None,
                 fpoc_params: dict | None = None, reward: str = 'infomax',
                 observe: str = 'belief', confidence: float = 0.95,
                 max_steps: int | None = None, start_cell: int | None = None,
                 render_mode: str | None = None, observation=None,
                 motion_sigma_cells: float = 0.0, jump_prob: float = 0.0,
                 absent_prior: float = 0.0, absent_rate: float = 0.0, scan: bool = True,
                 prior=None):
        if observation is not None:
            given = [name for name, value in (('spacing_deg', spacing_deg), ('fpoc', fpoc),
                                              ('fpoc_params', fpoc_params)) if value is not None]
            if given:
                raise ValueError(f"{', '.join(given)} cannot go with observation=: the "
                                 f'observation model brings its own grid and evidence')
            if isinstance(observation, (str, Path)):
                from ipomdp_gaze.files.observation_file import load_observation
                observation = load_observation(observation)
            if not (hasattr(observation, 'sample') and isinstance(getattr(observation, 'grid',
                                                                          None), Grid)):
                hint = ' (an FPOC goes in fpoc=)' if isinstance(observation, FPOC) else ''
                raise ValueError(f'observation must be an observation model with its grid, an '
                                 f'observation file or a shipped model name, got '
                                 f'{type(observation).__name__}{hint}')
            self.model = as_observation(observation.grid, observation)
            self.grid, self.fpoc = self.model.grid, getattr(self.model, 'fpoc', None)
            if (rows, cols) != (None, None) and (rows, cols) != self.grid.shape:
                raise ValueError(f'rows, cols ({rows}, {cols}) disagree with the observation '
                                 f"model's {self.grid.rows}x{self.grid.cols} grid")
        else:
            self.grid = Grid(7 if rows is None else rows, 7 if cols is None else cols,
                             DEFAULT_SPACING_DEG if spacing_deg is None else spacing_deg)
            fpoc = 'human' if fpoc is None else fpoc
            if fpoc_params is not None and not isinstance(fpoc_params, dict):
                raise ValueError(f'fpoc_params must be a dict of parameter names and values, '
                                 f'got {type(fpoc_params).__name__}')
            if isinstance(fpoc, FPOC) and fpoc_params:
                raise ValueError('fpoc_params cannot go with an FPOC object, which holds its '
                                 'parameters: give fpoc by name, or make_fpoc(model, **params)')
            self.fpoc = fpoc if isinstance(fpoc, FPOC) else make_fpoc(fpoc, **(fpoc_params or {}))
            self.model = GaussianObservation(self.grid, self.fpoc)
        check_sampling = getattr(self.model, 'check_sampling', None)
        if check_sampling is not None:      # frames the search would refuse, every one: as
            check_sampling()                # simulate, evaluate and train refuse the model
        if not isinstance(scan, (bool, np.bool_)):
            raise ValueError(f'scan must be True or False, got {scan!r}')
        self.scan = bool(scan) and getattr(self.model, 'has_scan', False)
        if reward not in REWARDS:
            raise ValueError(f"unknown reward {reward!r}; valid rewards: {', '.join(REWARDS)}")
        if observe not in OBSERVE:
            raise ValueError(f"unknown observe {observe!r}; valid: {', '.join(OBSERVE)}")
        if render_mode is not None and render_mode not in self.metadata['render_modes']:
            raise ValueError(f'unknown render_mode {render_mode!r}; valid: rgb_array, ansi')
        n = self.grid.n_cells
        # The agent chooses every fixation (no policy); the budget is the env's truncation.
        self.settings = SearchSettings(confidence=confidence, absent_prior=absent_prior,
                                       motion_sigma_cells=motion_sigma_cells,
                                       motion_jump_prob=jump_prob)
        self.session = SearchSession(self.grid, self.model, None, self.settings, prior=prior)
        self.prior = self.session.prior
        self.motion = self.session.motion
        self.absent_prior = self.settings.absent_prior
        self.absent_rate = check_probability(absent_rate, 'absent_rate')
        self.reward_name, self.observe = reward, observe
        self.confidence = self.settings.confidence
        self.max_steps = n if max_steps is None else \
            positive_int('max_steps', max_steps, allow_zero=True)
        if self.max_steps < 1:
            raise ValueError(f'max_steps must be at least 1, got {max_steps!r}')
        self.start_cell = self.grid.center_index if start_cell is None else \
            positive_int('start_cell', start_cell, allow_zero=True)
        if not 0 <= self.start_cell < n:
            raise ValueError(f'start_cell must be a cell index below {n}, got {start_cell!r}')
        self.render_mode = render_mode
        self.action_space = spaces.Discrete(n)
        if observe == 'belief':
            grid_space = spaces.Box(0.0, 1.0, shape=self.grid.shape, dtype=np.float64)
        else:
            grid_space = spaces.Box(-np.inf, np.inf, shape=self.grid.shape, dtype=np.float64)
        spaces_ = {observe: grid_space, 'fixation': spaces.Discrete(n)}
        if self.absent_prior > 0:
            spaces_['absent'] = spaces.Box(0.0, 1.0, shape=(1,), dtype=np.float64)
        self.observation_space = spaces.Dict(spaces_)
        self.session.reset()
        self._evidence = np.zeros(n)
        self._fixation = self.start_cell
        self._target = 0
        self._present = True
        self._steps = 0
        self._started = False

    belief = session_view(
        'belief', 'Return the cell probabilities, shape (N,) (summing to ``1 - P(absent)``).')
    absent_probability = session_view(
        'absent_probability', 'Return ``P(absent)`` (0 without the absent hypothesis).')

    def _obs(self):
        data = self.belief if self.observe == 'belief' else self._evidence
        obs = {self.observe: data.reshape(self.grid.shape).copy(), 'fixation': self._fixation}
        if self.absent_prior > 0:
            obs['absent'] = np.array([min(1.0, self.absent_probability)])
        return obs

    def _info(self, decision: str = ''):
        b = self.belief
        guess = int(map_cell(b))
        target = self._target if self._present else None
        return {'target': target, 'map_cell': guess, 'map_probability': float(b[guess]),
                'entropy': self.session.entropy_nats, 'steps': self._steps,
                'present': self._present, 'absent_probability': self.absent_probability,
                'decision': decision}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        n = self.grid.n_cells
        options = options or {}
        unknown = sorted(set(options) - RESET_OPTIONS)
        if unknown:
            raise ValueError(f'unknown reset option(s) {", ".join(map(repr, unknown))}; valid: '
                             f'{", ".join(sorted(RESET_OPTIONS))}')
        target = options.get('target')
        if target is not None and (isinstance(target, bool) or not isinstance(
                target, (int, np.integer)) or not 0 <= target < n):
            raise ValueError(f"options['target'] must be a cell index in [0, {n}), got "
                             f'{target!r}')
        if target is not None and self.prior is not None and self.prior[target] == 0:
            raise ValueError(f"options['target'] {target} is a cell the prior rules out "
                             '(probability 0)')
        self._target = int(draw_cells(self.np_random, n, self.prior)) if target is None \
            else int(target)
        if 'present' in options:
            if not isinstance(options['present'], (bool, np.bool_)):
                raise ValueError(f"options['present'] must be True or False, got "
                                 f"{options['present']!r}")
            if not options['present'] and self.absent_prior <= 0:
                raise ValueError("options['present'] False needs absent_prior > 0: without it "
                                 'the belief has no "nobody here" to find')
            self._present = bool(options['present'])
        else:
            self._present = self.absent_rate == 0 or \
                bool(self.np_random.random() >= self.absent_rate)
        self.session.reset()
        self._evidence = np.zeros(n)
        if self.scan:
            counts = self.model.sample_scan(self._target, self.np_random, present=self._present)
            self.session.scan(Frame(counts, kind='scan'))
            self._evidence = counts
        self.session.start()
        self._started = True
        self._fixation = self.start_cell
        self._steps = 0
        return self._obs(), self._info()

    def step(self, action):
        # The space's own test, which also takes numpy integers; a bool it would take as 0 or 1
        if isinstance(action, (bool, np.bool_)) or not self.action_space.contains(action):
            raise ValueError(
                f'action must be a cell index in [0, {self.grid.n_cells}), got {action!r}')
        k = int(action)
        if not self._started:
            raise gymnasium.error.ResetNeeded('call reset() before step()')
        if self.session.ended or self._steps >= self.max_steps:
            raise gymnasium.error.ResetNeeded('the episode has ended (terminated or truncated): '
                                              'call reset() before step()')
        obs = self.model.sample(self._target, k, self.np_random, present=self._present)
        self.session.fixate(k)
        result = self.session.update(Frame(obs))
        if not result.applied:              # the belief did not move: no step to report
            raise RuntimeError(f'the observation model drew a frame the search refused: '
                               f'{result.reason}')
        self._evidence, self._fixation = obs, k
        self._steps += 1
        if self.reward_name == 'infomax':
            reward = -self.session.entropy_nats
        else:
            reward = float(self.belief[k])
        info = self._info(result.decision)
        terminated = result.terminated
        truncated = bool(not terminated and self._steps >= self.max_steps)
        if self.motion.active:
            self._target = int(self.motion.move(np.array([self._target]), self.np_random)[0])
            self.session.predict(1.0)
        return self._obs(), reward, terminated, truncated, info

    def render(self):
        if self.render_mode == 'rgb_array':
            return belief_heatmap(self.belief, self.grid.shape, self._fixation)
        if self.render_mode == 'ansi':
            return belief_text(self.belief, *self.grid.shape, self._fixation)
        return None


def register_env() -> None:
    """Register :data:`ENV_ID` with Gymnasium (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point='ipomdp_gaze.simulation.gym:VisualSearchEnv')


register_env()
