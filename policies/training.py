# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
GPOMDP policy-gradient training of logistic and convolutional policies (docs/design.md sec. 3).

Per episode the eligibility trace is ``z_t = beta z_{t-1} + grad log pi(a_t | B_t)`` and the
gradient estimate ``g = sum_t r_t z_t`` (Baxter & Bartlett 2001); every epoch runs
``episodes_per_epoch`` episodes of horizon T (default N) and moves the weights by
``learning_rate * mean over the episodes of g``. The reward of step t is computed on the belief
after observation t.

All episodes of an epoch are simulated as one batch. The trace is never stored: summing by parts,
``g = sum_t r_t z_t = sum_s grad_s Q_s`` with ``Q_s = sum_{t >= s} beta^(t-s) r_t`` (the same
number, exactly), and ``grad log pi(a | B)`` of a logistic policy is the outer product
``(onehot(a) - p) B^T``, so the whole epoch's gradient is one matrix product
``sum_{t,e} Q (onehot - p) B^T``. The convolutional family ties every ``theta[k, j]`` with the same
squared displacement to one weight, so its gradient is the logistic gradient summed over each
tie class (27 weights at 7x7, 61 at 11x11).

Randomness: epoch ``i`` draws everything from ``numpy.random.default_rng([seed, i])``, so a run
resumed from a saved policy after epoch i continues exactly as the uninterrupted run.

Moving and absent targets (docs/design.md section 7): with ``motion_sigma_cells`` or
``jump_prob`` the training targets take a step of :class:`ipomdp_gaze.model.motion.Motion` after
every
fixation and the belief is predicted with it; ``absent_prior`` gives the belief the absent
hypothesis (the infomax reward is then over all N + 1 hypotheses; the policy sees the cells) and
``absent_rate`` empties that fraction of the training scenes. All four default to 0, which draws
exactly what the paper's task draws.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, field, replace
import math
from pathlib import Path
import time
from typing import Callable

from ipomdp_gaze.files.observation_file import fingerprint
from ipomdp_gaze.files.writable import write_file
from ipomdp_gaze.model.belief import check_prior, draw_cells
from ipomdp_gaze.model.checks import check_flag, positive_int
from ipomdp_gaze.model.fpoc import FPOC
from ipomdp_gaze.model.grid import Grid
from ipomdp_gaze.model.motion import check_probability, check_sigma_cells, Motion
from ipomdp_gaze.model.observation import as_observation, CountObservation
from ipomdp_gaze.model.stopping import BatchBelief, check_absent_prior
from ipomdp_gaze.simulation.evaluation import (fixations_to_90_ci, fixations_to_level,
                                               prior_chance, tracking_summary)
from ipomdp_gaze.simulation.simulate import rollout, simulate
import numpy as np

from .conv import ConvPolicy, kernel_from_radial, radial_bins
from .logistic import LogisticPolicy, sample_rows, softmax
from .policy_file import FAMILIES, observation_block, PolicyFileError, PolicySpec, REWARDS

CSV_FIELDS = ('epoch', 'episodes', 'mean_return', 'fixations_to_90', 'wall_seconds')


@dataclass(frozen=True)
class TrainConfig:
    """
    Hyper-parameters of a training run (all recorded in the policy file's training block).

    ``reward_scale`` multiplies every reward before the gradient (the paper does not state its
    scale); the step size of epoch i is ``learning_rate / (1 + i / anneal_epochs)`` (constant
    when ``anneal_epochs`` is None; the paper's "gamma_t can anneal over time"); ``baseline``
    subtracts a per-time-step reward baseline (the mean reward of the other episodes of the
    epoch at the same step, which keeps the estimate unbiased). ``motion_sigma_cells``,
    ``jump_prob``, ``absent_prior`` and ``absent_rate`` set the task of docs/design.md section 7
    (per fixation); ``prior``, rows of cells summing to 1, is where the target is a priori
    (drawn from it, and every belief starts at it; None: uniform, the paper's task).
    """

    reward: str = 'infomax'
    family: str = 'conv'
    learning_rate: float = 1.0
    reward_scale: float = 1.0
    anneal_epochs: float | None = None
    beta: float = 0.75
    episodes_per_epoch: int = 150
    horizon: int | None = None
    baseline: bool = False
    seed: int = 0
    eval_every: int = 50
    eval_episodes: int = 2000
    eval_seed: int = 1000003
    motion_sigma_cells: float = 0.0
    jump_prob: float = 0.0
    absent_prior: float = 0.0
    absent_rate: float = 0.0
    prior: tuple[tuple[float, ...], ...] | None = None

    def __post_init__(self):
        if self.reward not in REWARDS:
            raise ValueError(f"unknown reward {self.reward!r}; valid: {', '.join(REWARDS)}")
        if self.family not in FAMILIES:
            raise ValueError(f"unknown family {self.family!r}; valid: {', '.join(FAMILIES)}")
        for name in ('learning_rate', 'reward_scale'):
            value = getattr(self, name)
            if not (_is_number(value) and math.isfinite(value) and value > 0):
                raise ValueError(f'{name} must be a positive finite number, got {value!r}')
        if self.anneal_epochs is not None and not (
                _is_number(self.anneal_epochs) and self.anneal_epochs > 0):
            raise ValueError(f'anneal_epochs must be a positive number or None, '
                             f'got {self.anneal_epochs!r}')
        if not (_is_number(self.beta) and 0 <= self.beta < 1):
            raise ValueError(f'beta must be in [0, 1), got {self.beta!r}')
        # Counts and seeds whole (2.5 episodes was numpy's TypeError in the first epoch, a
        # horizon of 2.5 ran 2 fixations); the baseline a flag ('no' turned it on).
        for name in ('episodes_per_epoch', 'eval_every', 'eval_episodes'):
            positive_int(name, getattr(self, name))
        if self.horizon is not None:
            positive_int('horizon', self.horizon)
        for name in ('seed', 'eval_seed'):
            positive_int(name, getattr(self, name), allow_zero=True)
        check_flag(self.baseline, 'baseline')
        if self.episodes_per_epoch < 2 and self.baseline:
            raise ValueError('a reward baseline needs at least 2 episodes per epoch')
        check_sigma_cells(self.motion_sigma_cells, 'motion_sigma_cells')
        check_probability(self.jump_prob, 'jump_prob')
        check_absent_prior(self.absent_prior)
        check_probability(self.absent_rate, 'absent_rate')
        if self.prior is not None:
            object.__setattr__(self, 'prior', prior_rows(self.prior))

    def scene(self) -> dict:
        """Return the settings of docs/design.md section 7 that are not 0 (the paper's task)."""
        names = ('motion_sigma_cells', 'jump_prob', 'absent_prior', 'absent_rate')
        scene = {k: getattr(self, k) for k in names if getattr(self, k)}
        if self.prior is not None:
            scene['prior'] = [list(row) for row in self.prior]
        return scene


def _is_number(value) -> bool:
    """Whether ``value`` is a real number (numpy's too), not a bool or a string."""
    return isinstance(value, (int, float, np.integer, np.floating)) \
        and not isinstance(value, (bool, np.bool_))


def prior_rows(prior) -> tuple[tuple[float, ...], ...]:
    """
    Return a prior over the cells as rows of floats (hashable, as a policy file records it).

    ``prior`` is rows of cells (a nested sequence or a 2-D array); each value >= 0, summing to
    1 (:func:`ipomdp_gaze.simulation.simulate.check_prior`). ValueError (one line) otherwise.
    """
    try:
        values = np.array(prior, dtype=float)
    except (TypeError, ValueError):
        raise ValueError('prior must be rows of numbers, one per cell') from None
    if values.ndim != 2 or values.size == 0:
        raise ValueError(f'prior must be rows of cells (rows x cols numbers), got shape '
                         f'{values.shape}')
    check_prior(values, values.size, values.shape)
    return tuple(tuple(float(v) for v in row) for row in values)


@dataclass
class EpochResult:
    """What one epoch produced: the mean gradient (over episodes) and the returns."""

    gradient: np.ndarray
    returns: np.ndarray


@dataclass
class Episodes:
    """
    A batch of sampled episodes: what the gradient needs, stacked over time steps.

    ``belief[t, e]`` is B_t (before fixation t), ``delta[t, e] = onehot(a_t) - p(. | B_t)`` and
    ``reward[t, e]`` the (unscaled) reward on the belief after observation t.
    """

    belief: np.ndarray
    delta: np.ndarray
    reward: np.ndarray
    fixations: np.ndarray = field(default=None)


class Family:
    """Maps a family's parameter vector to the N x N matrix ``theta[k, j]`` and back."""

    def __init__(self, grid: Grid, name: str):
        self.grid = grid
        self.name = name
        if name == 'conv':
            values, bins = radial_bins(grid)
            ri, ci = grid.pair_offset_index()
            self.squared_distance = values
            self.pair_bins = np.ascontiguousarray(bins[ri, ci])      # [k, j]
            self.size = values.size
        else:
            self.size = grid.n_cells ** 2

    def theta(self, params: np.ndarray) -> np.ndarray:
        """Expand a parameter vector into the N x N matrix ``theta[k, j]``."""
        if self.name == 'conv':
            return params[self.pair_bins]
        n = self.grid.n_cells
        return params.reshape(n, n)

    def project(self, grad_theta: np.ndarray) -> np.ndarray:
        """Gradient with respect to the parameters from the gradient with respect to theta."""
        if self.name == 'conv':
            return np.bincount(self.pair_bins.ravel(), weights=grad_theta.ravel(),
                               minlength=self.size)
        return grad_theta.ravel().copy()

    def policy(self, params: np.ndarray, action: str = 'argmax'):
        """Build the policy object with these parameters."""
        if self.name == 'conv':
            return ConvPolicy(self.grid, kernel_from_radial(self.grid, params), action=action)
        return LogisticPolicy(self.grid, self.theta(params), action=action)

    def params_from_spec(self, spec: PolicySpec) -> np.ndarray:
        """Read the parameter vector stored in a policy file."""
        if self.name == 'conv':
            radial = spec.radial()
            if radial is None:
                raise ValueError('cannot resume a conv policy whose kernel is not radially '
                                 'weight-shared')
            return np.asarray(radial['weight'], dtype=float)
        return np.asarray(spec.theta, dtype=float).ravel().copy()


def elm_init(grid: Grid, model, scale: float) -> np.ndarray:
    """
    Conv parameters that start training at ELM: ``scale`` times ELM's kernel, radially averaged.

    ELM is itself a conv kernel (docs/design.md section 3.2): ``scores = B * K_ELM``. Its
    kernel averaged over each distinct squared distance is in the conv family; ``scale`` sets the
    softmax's sharpness (large: nearly ELM's argmax choices; policy gradient needs some spread).
    """
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f'the ELM initialisation scale must be a positive number, got {scale!r}')
    values, bins = radial_bins(grid)
    kernel = as_observation(grid, model).elm_kernel()
    weight = np.bincount(bins.ravel(), weights=kernel.ravel(), minlength=values.size) \
        / np.bincount(bins.ravel(), minlength=values.size)
    with np.errstate(over='ignore'):
        params = scale * weight
    if not np.all(np.isfinite(params)):
        raise ValueError(f'the ELM initialisation scale {scale:g} makes the kernel overflow: '
                         'give a smaller one')
    return params


def sample_episodes(theta: np.ndarray, model, reward: str, episodes: int,
                    horizon: int, rng: np.random.Generator, motion: Motion | None = None,
                    absent_prior: float = 0.0, absent_rate: float = 0.0,
                    scan: bool = True, prior: np.ndarray | None = None) -> Episodes:
    """
    Run a batch of episodes with the softmax policy ``p(k | B) ∝ exp(theta[k] . B)``.

    Parameters
    ----------
    theta : array (N, N)
        ``theta[k, j]``.
    model
        The observation model the frames are drawn from (:mod:`ipomdp_gaze.model.observation`).
    reward : {'infomax', 'fixate_target'}
        The reward computed on the belief after each observation.
    episodes, horizon : int
        Batch size and fixations per episode.
    rng : numpy.random.Generator
        Source of the targets, the observation noise and the policy's samples (and, when they
        are on, of the empty scenes and the target's steps).
    motion : Motion, optional
        The target's step after every fixation; the belief is predicted with it.
    absent_prior, absent_rate : float
        The belief's prior that no target is in the grid, and the fraction of empty scenes.
    scan : bool
        With a count model that has scan tables, first apply the one-time scan (drawn from the
        scan tables), as ``find`` does: the policy learns from the beliefs it will see.
    prior : array (N,), optional
        Where the target is a priori, summing to 1 (:func:`check_prior`): the targets are drawn
        from it and every belief starts at it (default uniform, drawn as before it existed).

    """
    n = theta.shape[0]
    rows = np.arange(episodes)
    theta_t = np.ascontiguousarray(theta.T)
    if prior is not None:
        prior = check_prior(prior, n)
    targets = draw_cells(rng, n, prior, episodes)
    present = rng.random(episodes) >= absent_rate if absent_rate > 0 else None
    moving = motion is not None and motion.active
    batch = BatchBelief(n, absent_prior, episodes, moving, prior)
    belief = batch.belief
    if scan and getattr(model, 'has_scan', False):
        frames = model.sample_scan(targets, rng, present=present)
        batch.update(model.scan_log_likelihood_ratio(frames, validate=False))
    beliefs = np.empty((horizon, episodes, n))
    delta = np.empty((horizon, episodes, n))
    rewards = np.empty((horizon, episodes))
    fixations = np.empty((horizon, episodes), dtype=np.int64)

    def choose(t):
        beliefs[t] = belief
        p = softmax(belief @ theta_t)
        a = sample_rows(p, rng)
        fixations[t] = a
        np.negative(p, out=delta[t])
        delta[t, rows, a] += 1.0
        return a

    def record(t, a, gain, where):
        rewards[t] = gain if reward == 'infomax' else belief[rows, a]

    rollout(model, batch, targets, present, horizon, choose, lambda t: rng, record,
            motion=motion if moving else None, steps=lambda t: rng)
    return Episodes(beliefs, delta, rewards, fixations)


def discounted_from(rewards: np.ndarray, beta: float) -> np.ndarray:
    """``Q_s = sum_{t >= s} beta^(t-s) r_t`` along axis 0 (time)."""
    q = np.empty_like(rewards)
    acc = np.zeros(rewards.shape[1:])
    for t in range(rewards.shape[0] - 1, -1, -1):
        acc = rewards[t] + beta * acc
        q[t] = acc
    return q


def leave_one_out_mean(rewards: np.ndarray) -> np.ndarray:
    """Per time step, the mean reward of the other episodes (axis 1) of the batch."""
    e = rewards.shape[1]
    return (rewards.sum(axis=1, keepdims=True) - rewards) / (e - 1)


def theta_gradient(batch: Episodes, beta: float, reward_scale: float = 1.0,
                   baseline: bool = False) -> np.ndarray:
    """Mean over episodes of ``g = sum_t r_t z_t`` with respect to the N x N theta."""
    r = reward_scale * batch.reward
    if baseline:
        r = r - leave_one_out_mean(r)
    q = discounted_from(r, beta)
    n = batch.belief.shape[-1]
    weighted = (batch.delta * q[:, :, None]).reshape(-1, n)
    return weighted.T @ batch.belief.reshape(-1, n) / batch.reward.shape[1]


def trace_gradient_reference(batch: Episodes, beta: float, reward_scale: float = 1.0,
                             baseline: bool = False) -> np.ndarray:
    """Compute the same estimate literally with the eligibility trace (for tests; slow)."""
    r = reward_scale * batch.reward
    if baseline:
        r = r - leave_one_out_mean(r)
    horizon, episodes, n = batch.belief.shape
    total = np.zeros((n, n))
    for e in range(episodes):
        z = np.zeros((n, n))
        for t in range(horizon):
            z = beta * z + np.outer(batch.delta[t, e], batch.belief[t, e])
            total += r[t, e] * z
    return total / episodes


def log_policy_gradient(theta: np.ndarray, belief: np.ndarray, action: int) -> np.ndarray:
    """``grad_theta log p(action | belief)`` of the logistic policy, shape (N, N)."""
    p = softmax(belief @ theta.T)
    onehot = np.zeros_like(p)
    onehot[action] = 1.0
    return np.outer(onehot - p, belief)


class Trainer:
    """
    Trains one policy on one task; call :meth:`run` as often as needed (it resumes).

    Parameters
    ----------
    grid, fpoc : the task.
    config : TrainConfig
    params : array, optional
        Initial parameter vector (radial weights or flattened theta); zeros (a uniformly random
        policy) when omitted: training from scratch.
    epoch : int
        Epochs already done (when resuming).

    """

    def __init__(self, grid: Grid, fpoc: FPOC, config: TrainConfig,
                 params: np.ndarray | None = None, epoch: int = 0, wall_seconds: float = 0.0,
                 init: str = 'zeros'):
        self.grid = grid
        self.init = str(init)
        self.model = as_observation(grid, fpoc)
        self.fpoc = getattr(self.model, 'fpoc', None)          # None for a count model
        self.config = config
        self.family = Family(grid, config.family)
        if params is None:
            params = np.zeros(self.family.size)
        params = np.array(params, dtype=float).ravel()
        if params.size != self.family.size:
            raise ValueError(f'{config.family} parameters must have {self.family.size} values, '
                             f'got {params.size}')
        self.params = params
        self.epoch = int(epoch)
        self.wall_seconds = float(wall_seconds)
        self.horizon = grid.n_cells if config.horizon is None else int(config.horizon)
        self.motion = Motion(grid, config.motion_sigma_cells, config.jump_prob)
        self.prior = None
        if config.prior is not None:
            self.prior = check_prior(np.array(config.prior), grid.n_cells, grid.shape)
        self.curve: list[dict] = []

    def epoch_rng(self, epoch: int) -> np.random.Generator:
        """Return the generator of epoch ``epoch`` (0-based)."""
        return np.random.default_rng([self.config.seed, epoch])

    def learning_rate(self, epoch: int) -> float:
        """Return the step size of epoch ``epoch`` (0-based)."""
        cfg = self.config
        if cfg.anneal_epochs is None:
            return cfg.learning_rate
        return cfg.learning_rate / (1.0 + epoch / cfg.anneal_epochs)

    def step(self) -> EpochResult:
        """Run one epoch and update the parameters."""
        cfg = self.config
        batch = sample_episodes(self.family.theta(self.params), self.model, cfg.reward,
                                cfg.episodes_per_epoch, self.horizon, self.epoch_rng(self.epoch),
                                self.motion, cfg.absent_prior, cfg.absent_rate,
                                prior=self.prior)
        grad = self.family.project(theta_gradient(batch, cfg.beta, cfg.reward_scale,
                                                  cfg.baseline))
        self.params += self.learning_rate(self.epoch) * grad
        self.epoch += 1
        return EpochResult(grad, batch.reward.sum(axis=0))

    def evaluate(self, episodes: int | None = None, seed: int | None = None):
        """Fixations to 90% correct of the argmax policy on a fixed evaluation set."""
        cfg = self.config
        result = simulate(self.grid, self.model, self.family.policy(self.params, 'argmax'),
                          cfg.eval_episodes if episodes is None else episodes, self.horizon,
                          cfg.eval_seed if seed is None else seed, motion=self.motion,
                          absent_prior=cfg.absent_prior, absent_rate=cfg.absent_rate,
                          prior=self.prior)
        return fixations_to_level(result.percent_correct, self.grid.n_cells,
                                  chance=prior_chance(self.prior))

    def run(self, epochs: int, progress=False,
            callback: Callable[[dict], None] | None = None) -> list[dict]:
        """
        Train ``epochs`` more epochs, with a learning-curve row every ``eval_every`` epochs.

        A row is added after the last epoch too, so that a run shorter than ``eval_every`` (or
        not a multiple of it) still ends its curve with an evaluation.

        A row is ``{epoch, episodes, mean_return, fixations_to_90, wall_seconds}``: the mean
        return (sum of the unscaled rewards of an episode, sampled policy) over the epochs since
        the previous row, and fixations to 90% correct of the argmax policy on the fixed
        evaluation set (None if never reached). ``callback(row)`` is called after each row.
        Evaluation time is not counted in ``wall_seconds``. ``progress`` True shows the epochs,
        the mean return and fixations to 90% on stderr
        (:class:`ipomdp_gaze.simulation.progress.Progress`:
        a bar on a terminal, a line every few seconds otherwise); or pass a ``Progress``.
        """
        cfg = self.config
        bar = None
        if progress is True:
            from ipomdp_gaze.simulation.progress import Progress
            bar = Progress(epochs, 'train', 'epoch')
        elif progress:
            bar = progress
        returns = []
        f90_text = '-'
        start = time.perf_counter()

        def add_row():
            nonlocal returns, f90_text, start
            self.wall_seconds += time.perf_counter() - start
            f90 = self.evaluate()
            row = {'epoch': self.epoch, 'episodes': self.epoch * cfg.episodes_per_epoch,
                   'mean_return': float(np.mean(returns)), 'fixations_to_90': f90,
                   'wall_seconds': round(self.wall_seconds, 3)}
            self.curve.append(row)
            returns = []
            f90_text = 'never' if f90 is None else f'{f90:.2f}'
            if callback is not None:
                callback(row)
            start = time.perf_counter()
        try:
            for i in range(epochs):
                returns.append(float(self.step().returns.mean()))
                last_return = returns[-1]
                # Every eval_every epochs, and after the last one: a run shorter than
                # eval_every (or not a multiple of it) still ends its curve with an evaluation.
                if self.epoch % cfg.eval_every == 0 or i == epochs - 1:
                    add_row()
                if bar is not None:
                    bar.note(f'epoch {self.epoch}, return {last_return:.3f}, '
                             f'fix->90% {f90_text}')
                    bar.update(1)
        finally:
            self.wall_seconds += time.perf_counter() - start
            if bar is not None and progress is True:
                bar.close()
        return self.curve

    def spec(self, action: str = 'argmax', evaluation: dict | None = None) -> PolicySpec:
        """Return the policy file contents for the current parameters."""
        cfg = self.config
        training = {'epochs': self.epoch, 'episodes_per_epoch': cfg.episodes_per_epoch,
                    'learning_rate': cfg.learning_rate, 'anneal_epochs': cfg.anneal_epochs,
                    'reward_scale': cfg.reward_scale,
                    'beta': cfg.beta, 'horizon': self.horizon, 'baseline': cfg.baseline,
                    'seed': cfg.seed, 'init': self.init, 'eval_every': cfg.eval_every,
                    'eval_episodes': cfg.eval_episodes, 'eval_seed': cfg.eval_seed,
                    'wall_seconds': round(self.wall_seconds, 3), **cfg.scene()}
        kernel = theta = None
        if cfg.family == 'conv':
            kernel = kernel_from_radial(self.grid, self.params)
        else:
            theta = self.family.theta(self.params).copy()
        observation = None
        if isinstance(self.model, CountObservation):
            observation = observation_block(self.model)
        return PolicySpec(grid=self.grid, fpoc=self.fpoc, reward=cfg.reward, family=cfg.family,
                          action=action, observation=observation, kernel=kernel, theta=theta,
                          training=training, evaluation=dict(evaluation or {}))


def config_from_spec(spec: PolicySpec, **overrides) -> TrainConfig:
    """
    Read the training configuration of a policy file, with ``overrides`` applied.

    A recorded setting that :class:`TrainConfig` refuses (a hand-edited ``beta: x``) is a
    :class:`PolicyFileError` naming the file and ``training.<setting>``.
    """
    known = set(TrainConfig.__dataclass_fields__)
    recorded = {k: v for k, v in spec.training.items() if k in known}
    recorded.update(reward=spec.reward, family=spec.family)
    if recorded.get('horizon') == spec.grid.n_cells:
        recorded['horizon'] = None
    try:
        config = TrainConfig(**recorded)
    except ValueError as exc:
        where = f'{spec.path}: ' if spec.path is not None else ''
        text = str(exc)
        named = text.split(' ', 1)[0] in known
        raise PolicyFileError(f"{where}training{'.' if named else ': '}{text}") from None
    return replace(config, **{k: v for k, v in overrides.items() if v is not None})


def trainer_from_spec(spec: PolicySpec, model=None, **overrides) -> Trainer:
    """
    Build a trainer that resumes a saved policy (its weights, epoch count and settings).

    ``model`` is the observation model of a policy trained on a count model (the file names
    it by fingerprint only); an FPOC-trained policy uses its own FPOC.
    """
    config = config_from_spec(spec, **overrides)
    family = Family(spec.grid, config.family)
    if spec.observation is not None:
        if not isinstance(model, CountObservation) or \
                fingerprint(model) != spec.observation['sha256']:
            raise ValueError('resuming a policy trained on a count model needs that model')
    else:
        model = spec.fpoc
    return Trainer(spec.grid, model, config, params=family.params_from_spec(spec),
                   epoch=int(spec.training.get('epochs', 0)),
                   wall_seconds=float(spec.training.get('wall_seconds', 0.0)),
                   init=str(spec.training.get('init', 'zeros')))


def write_curve(path, rows: list[dict], append: bool = False) -> Path:
    """Write (or append to) a learning-curve CSV with columns :data:`CSV_FIELDS`."""
    path = Path(path)
    exists = append and path.is_file()

    def write(out: Path) -> None:
        with out.open('a' if exists else 'w', newline='') as fh:
            writer = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
            if not exists:
                writer.writeheader()
            for row in rows:
                writer.writerow({k: ('' if row.get(k) is None else row[k]) for k in CSV_FIELDS})

    if exists:
        write(path)
    else:
        write_file(path, write)     # whole or not at all: a resumed training reads it back
    return path


def read_curve(path) -> list[dict]:
    """Read a learning-curve CSV back (numbers as floats, blank as None)."""
    def value(key, text):
        if text == '':
            return None
        return int(text) if key in ('epoch', 'episodes') else float(text)

    with Path(path).open(newline='') as fh:
        return [{k: value(k, v) for k, v in row.items()} for row in csv.DictReader(fh)]


def evaluation_block(grid: Grid, fpoc: FPOC, policy, episodes: int = 20000, seed: int = 0,
                     horizon: int | None = None, bootstrap: int = 1000,
                     scene: dict | None = None, progress=None) -> dict:
    """
    Fixations to 90% correct with a 95% bootstrap interval, as a policy file records it.

    Uses the same targets, noise and bootstrap draws as ``ipomdp-gaze evaluate --seed SEED``, so
    the numbers match that command's. ``scene`` holds the settings of docs/design.md section 7
    (:meth:`TrainConfig.scene`); they are recorded, and a moving target adds its tracking
    accuracy (:func:`ipomdp_gaze.simulation.evaluation.tracking_summary`). ``progress``
    (``update(n)``)
    counts the fixations simulated.
    """
    scene = dict(scene or {})
    horizon = grid.n_cells if horizon is None else int(horizon)
    motion = Motion(grid, scene.get('motion_sigma_cells', 0.0), scene.get('jump_prob', 0.0))
    prior = scene.get('prior')
    if prior is not None:
        prior = check_prior(np.array(prior), grid.n_cells, grid.shape)
    result = simulate(grid, fpoc, policy, episodes, horizon, seed, motion=motion,
                      absent_prior=scene.get('absent_prior', 0.0),
                      absent_rate=scene.get('absent_rate', 0.0), prior=prior,
                      progress=None if progress is None else lambda t: progress.update(1))
    point, ci = fixations_to_90_ci(result.correct, grid.n_cells,
                                   np.random.default_rng([seed, 99]), bootstrap,
                                   chance=prior_chance(prior))
    block = {'episodes': int(episodes), 'seed': int(seed), 'action': policy.action,
             'horizon': horizon, 'fixations_to_90': point, 'ci95': list(ci) if ci else None}
    block.update(scene)
    if motion.active:
        tracking = tracking_summary(result, grid.cols, np.random.default_rng([seed, 98]),
                                    bootstrap)['tracking_accuracy']
        block['tracking_accuracy'] = tracking['value']
        block['tracking_accuracy_ci95'] = tracking['ci95']
    return block
