# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze train``: learn a policy by GPOMDP policy gradient and write its policy file.

Writes ``PATH.yaml`` (the policy, its training record and, at the end, its evaluation on
``--final-episodes`` episodes) and the learning curve ``PATH.csv`` beside it. Both are rewritten
at every evaluation point, so an interrupted run resumes with ``--resume PATH.yaml``.
"""
from __future__ import annotations

import argparse
from pathlib import Path
import sys

from ipomdp_gaze.model.belief import prior_is_uniform
from ipomdp_gaze.model.wording import counted
from ipomdp_gaze.search.session import SearchSettings

from .common import (add_prior_arg, add_task_args, check_output_file, count_in,
                     MAX_EPISODES, MAX_EPOCH_EPISODES, MAX_EPOCHS, nonneg_int, number_arg,
                     output_file, positive_float, positive_int, read_prior, task_from_args)
from .running import add_run_args, executor_from_args, progress_from_args
from .search_args import add_scene_args, settings_from_args

FAMILY_DEFAULT, REWARD_DEFAULT = 'conv', 'infomax'
EPOCHS = count_in(0, MAX_EPOCHS, f'a number of epochs from 0 to {MAX_EPOCHS}')
EPOCH_EPISODES = count_in(1, MAX_EPOCH_EPISODES,
                          f'a number of episodes from 1 to {MAX_EPOCH_EPISODES}')
EVAL_EPISODES = count_in(1, MAX_EPISODES, f'a number of episodes from 1 to {MAX_EPISODES}')
FINAL_EPISODES = count_in(0, MAX_EPISODES, f'a number of episodes from 0 to {MAX_EPISODES}')
# The defaults of the learning rate and reward scale: chosen on the 7x7 human task (README).
LEARNING_RATE = 5.0
REWARD_SCALE = 1.0


def add_parser(sub):
    p = sub.add_parser('train', help='learn a policy by policy gradient (GPOMDP)',
                       description='Train a convolutional (radially weight-shared) or full '
                                   'logistic policy from a zero kernel, or resume one; write the '
                                   'policy file and a learning-curve CSV beside it.')
    add_task_args(p)
    p.set_defaults(grid=None, spacing_deg=None, fpoc=None)
    p.add_argument('--reward', choices=('infomax', 'fixate_target'), default=None,
                   help=f'reward (default {REWARD_DEFAULT})')
    p.add_argument('--family', choices=('conv', 'logistic'), default=None,
                   help=f'policy family (default {FAMILY_DEFAULT})')
    p.add_argument('--epochs', type=EPOCHS, required=True,
                   help='total epochs; with --resume, training continues up to this count')
    p.add_argument('--seed', type=nonneg_int, default=None, help='training seed (default 0)')
    p.add_argument('--out', type=output_file, default=None, metavar='PATH.yaml',
                   help='policy file to write (default: the --resume file)')
    p.add_argument('--resume', type=Path, default=None, metavar='PATH.yaml',
                   help='continue training the policy in this file with its recorded settings')
    p.add_argument('--init-elm', type=positive_float, default=None, metavar='SCALE',
                   help="start a conv kernel at SCALE times ELM's kernel (radially averaged) "
                        'instead of zeros')
    p.add_argument('--learning-rate', type=positive_float, default=None,
                   help=f'step size of theta += lr * mean g (default {LEARNING_RATE})')
    p.add_argument('--anneal-epochs', type=positive_float, default=None, metavar='TAU',
                   help='anneal the step size as lr / (1 + epoch / TAU) (default: constant)')
    p.add_argument('--reward-scale', type=positive_float, default=None,
                   help=f'factor applied to every reward (default {REWARD_SCALE})')
    p.add_argument('--beta', type=number_arg, default=None, help='eligibility trace decay (0.75)')
    p.add_argument('--baseline', dest='baseline', action='store_true', default=None,
                   help='subtract a per-time-step reward baseline (the default)')
    p.add_argument('--no-baseline', dest='baseline', action='store_false',
                   help='plain GPOMDP without a baseline')
    p.add_argument('--horizon', type=positive_int, default=None,
                   help='fixations per training episode (default N, the number of cells)')
    p.add_argument('--episodes-per-epoch', type=EPOCH_EPISODES, default=None,
                   help='episodes pooled per update (default 150, the paper)')
    p.add_argument('--eval-every', type=positive_int, default=None, metavar='K',
                   help='evaluate the argmax policy every K epochs (default 50)')
    p.add_argument('--eval-episodes', type=EVAL_EPISODES, default=None,
                   help='episodes of the fixed evaluation set used during training '
                        '(default 2000)')
    p.add_argument('--final-episodes', type=FINAL_EPISODES, default=20000,
                   help='episodes of the final evaluation written to the file (default 20000; '
                        '0 skips it)')
    p.add_argument('--final-seed', type=nonneg_int, default=0,
                   help='seed of the final evaluation (default 0, as ipomdp-gaze evaluate)')
    add_scene_args(p, 'training')
    add_prior_arg(p, 'the training targets are drawn from it, every belief starts at it, and '
                     'the policy file records it')
    p.add_argument('--seeds', type=_list(nonneg_int), default=None, metavar='S,...',
                   help='a sweep: train one policy per seed (and per --learning-rates value) '
                        'on the workers of --jobs / --scheduler, write PATH-seedS.yaml each and '
                        'report the spread of their fixations to 90%%')
    p.add_argument('--learning-rates', type=_list(positive_float), default=None,
                   metavar='LR,...', help='a sweep over these step sizes (with --seeds, every '
                                          'pair; files PATH-seedS-lrLR.yaml)')
    add_run_args(p, '; used by a --seeds / --learning-rates sweep')
    p.set_defaults(run=run)


def _list(kind):
    """Parse ``a,b,...`` into a list of ``kind`` (its own message for a bad item)."""
    def parse(text: str) -> list:
        values = [kind(item) for item in text.split(',') if item.strip()]
        if not values:
            raise argparse.ArgumentTypeError(f'expected a comma-separated list, got {text!r}')
        if len(set(values)) != len(values):
            raise argparse.ArgumentTypeError(f'each value once (one training each), got {text!r}')
        return values
    return parse


def _task(args, spec):
    """Return the task of the command line or of the resumed file (explicit options must agree)."""
    from ipomdp_gaze.model.fpoc import make_fpoc
    from ipomdp_gaze.model.grid import Grid
    from ipomdp_gaze.policies.policy_file import PolicyFileError
    if spec is None:
        return task_from_args(args)
    if spec.observation is not None or args.observation:
        return _count_task(args, spec)
    given = {
        'grid': args.grid is not None and tuple(args.grid) != spec.grid.shape,
        'spacing-deg': args.spacing_deg is not None
        and args.spacing_deg != spec.grid.spacing_deg,
        'fpoc': args.fpoc is not None and args.fpoc != spec.fpoc.model,
        'reward': args.reward is not None and args.reward != spec.reward,
        'family': args.family is not None and args.family != spec.family,
    }
    clash = [name for name, differs in given.items() if differs]
    if clash:
        raise PolicyFileError(f'--{clash[0]} differs from the resumed file {args.resume} '
                              '(drop it to continue the task of the file)')
    if args.fpoc_param:
        params = {**spec.fpoc.params(), **dict(args.fpoc_param)}
        if make_fpoc(spec.fpoc.model, **params) != spec.fpoc:
            raise PolicyFileError(f'--fpoc-param differs from the resumed file {args.resume}')
    return Grid(spec.grid.rows, spec.grid.cols, spec.grid.spacing_deg), spec.fpoc


def _count_task(args, spec):
    """Return the count model of a resumed file: ``--observation`` must give the same one."""
    from ipomdp_gaze.files.observation_file import fingerprint, load_observation
    from ipomdp_gaze.policies.policy_file import PolicyFileError
    if spec.observation is None:
        raise PolicyFileError(f'--observation differs from the resumed file {args.resume} '
                              f'(trained on an FPOC)')
    name = spec.observation.get('name') or 'its count model'
    if not args.observation:
        raise PolicyFileError(f'{args.resume} was trained on {name}: give it with '
                              f'--observation FILE to resume')
    for option, value in (('grid', args.grid), ('fpoc', args.fpoc),
                          ('fpoc-param', args.fpoc_param), ('spacing-deg', args.spacing_deg)):
        if value:
            raise PolicyFileError(f'--{option} cannot be combined with --observation')
    model = load_observation(args.observation)
    if fingerprint(model) != spec.observation['sha256']:
        raise PolicyFileError(f'--observation {args.observation} is not the model {args.resume} '
                              f'was trained on ({name})')
    if args.reward is not None and args.reward != spec.reward or \
            args.family is not None and args.family != spec.family:
        raise PolicyFileError(f'--reward/--family differ from the resumed file {args.resume}')
    return model.grid, model


# The flag of each training setting a resumed training keeps (_refuse_changed_training).
RESUME_FLAGS = {'learning_rate': '--learning-rate', 'anneal_epochs': '--anneal-epochs',
                'reward_scale': '--reward-scale', 'beta': '--beta',
                'baseline': '--baseline/--no-baseline', 'seed': '--seed',
                'episodes_per_epoch': '--episodes-per-epoch', 'horizon': '--horizon',
                'eval_every': '--eval-every', 'eval_episodes': '--eval-episodes',
                'motion_sigma_cells': '--motion-sigma-cells', 'jump_prob': '--jump-prob',
                'absent_prior': '--absent-prior', 'absent_rate': '--absent-rate',
                'prior': '--prior'}


def config_prior(spec):
    """Return the prior a policy file's training records (rows), or None (uniform)."""
    from ipomdp_gaze.policies.training import config_from_spec
    return config_from_spec(spec).prior


def _same_prior(given, recorded) -> bool:
    """Whether ``--prior``'s rows are the recorded prior; a uniform file is the uniform prior."""
    if prior_is_uniform(given) and prior_is_uniform(recorded):
        return True
    return given == recorded


def _refuse_changed_training(args, spec, overrides: dict) -> None:
    """
    Refuse training settings given with ``--resume`` that differ from the file's (ValueError).

    A resumed training continues exactly like an uninterrupted one (docs/design.md section
    3.4): with other settings its record would describe every epoch by the last ones.
    """
    from ipomdp_gaze.policies.training import config_from_spec
    recorded = config_from_spec(spec)

    def shown(value):
        return 'the default' if value is None else repr(value)

    def given(key, value):
        if key == 'prior':                  # rows of numbers: the file, and which was recorded
            return (f'--prior {args.prior} (recorded: '
                    f'{"uniform" if prior_is_uniform(recorded.prior) else "another prior"})')
        return f'{RESUME_FLAGS[key]} {value!r} (recorded: {shown(getattr(recorded, key))})'

    changed = [given(key, value) for key, value in overrides.items()
               if value is not None and value != getattr(recorded, key)]
    if changed:
        raise ValueError(f'--resume {args.resume} continues the training as the file records '
                         f'it, but {"; ".join(changed)}: leave them out, or start a new '
                         'training with --out')


def run(args) -> int:
    from ipomdp_gaze.policies.policy_file import load_policy_spec, save_policy
    from ipomdp_gaze.policies.training import (evaluation_block, read_curve, TrainConfig, Trainer,
                                               trainer_from_spec, write_curve)
    settings_from_args(args, SearchSettings())       # bad settings: refused before any work
    spec = load_policy_spec(args.resume) if args.resume is not None else None
    out = args.out if args.out is not None else args.resume
    if out is None:
        raise ValueError('--out PATH.yaml is required (or --resume PATH.yaml)')
    if out.suffix != '.yaml':
        if args.out is None:
            raise ValueError(f'--resume {args.resume}: give --out PATH.yaml for the resumed '
                             'policy (it is written there, with its learning curve)')
        raise ValueError(f'--out must end in .yaml, got {out}')
    flag = '--out' if args.out is not None else '--resume'        # --resume writes over itself
    check_output_file(flag, out)
    check_output_file(flag, out.with_suffix('.csv'))
    grid, fpoc = _task(args, spec)
    prior = None
    if args.prior is not None:
        from ipomdp_gaze.policies.training import prior_rows
        prior = prior_rows(read_prior(args.prior, grid).reshape(grid.shape))
    overrides = {
        'learning_rate': args.learning_rate, 'anneal_epochs': args.anneal_epochs,
        'reward_scale': args.reward_scale,
        'beta': args.beta, 'baseline': args.baseline, 'seed': args.seed,
        'episodes_per_epoch': args.episodes_per_epoch, 'horizon': args.horizon,
        'eval_every': args.eval_every,
        'eval_episodes': args.eval_episodes, 'motion_sigma_cells': args.motion_sigma_cells,
        'jump_prob': args.motion_jump_prob, 'absent_prior': args.absent_prior,
        'absent_rate': args.absent_rate, 'prior': prior}
    sweep = args.seeds is not None or args.learning_rates is not None
    if sweep and spec is not None:
        raise ValueError('--seeds / --learning-rates start new trainings: drop --resume')
    if spec is None:
        defaults = {'reward': args.reward or REWARD_DEFAULT,
                    'family': args.family or FAMILY_DEFAULT, 'learning_rate': LEARNING_RATE,
                    'reward_scale': REWARD_SCALE, 'baseline': True}
        defaults.update({k: v for k, v in overrides.items() if v is not None})
        config = TrainConfig(**defaults)
        if args.epochs == 0 and args.init_elm is None:
            raise ValueError('--epochs 0 trains nothing: give a positive count (or --init-elm '
                             'SCALE to write the initial ELM kernel)')
        params, init = None, 'zeros'
        if args.init_elm is not None:
            if config.family != 'conv':
                raise ValueError('--init-elm starts a conv kernel: use it with --family conv')
            from ipomdp_gaze.policies.training import elm_init
            try:
                params = elm_init(grid, fpoc, args.init_elm)
            except ValueError as exc:
                raise ValueError(f'--init-elm {args.init_elm:g}: {exc}') from None
            init = f'elm x {args.init_elm:g}'
        if sweep:
            return run_sweep(args, grid, fpoc, config, params, init, out)
        trainer = Trainer(grid, fpoc, config, params=params, init=init)
    else:
        if args.init_elm is not None:
            raise ValueError('--init-elm starts a new training; a resumed one keeps its kernel')
        if prior is not None and _same_prior(prior, config_prior(spec)):
            overrides['prior'] = None       # the recorded one, kept as it is (bit for bit)
        _refuse_changed_training(args, spec, overrides)
        trainer = trainer_from_spec(spec, model=fpoc, **overrides)
    curve_path = out.with_suffix('.csv')
    rows = []
    if spec is not None and args.resume.with_suffix('.csv').is_file():
        rows = [r for r in read_curve(args.resume.with_suffix('.csv'))
                if r['epoch'] <= trainer.epoch]
    remaining = args.epochs - trainer.epoch
    if remaining < 0:
        raise ValueError(f'--epochs {args.epochs} is less than the {trainer.epoch} epochs '
                         f'already trained in {args.resume}')

    def checkpoint(row=None):
        if row is not None:
            rows.append(row)
        save_policy(out, trainer.spec())
        write_curve(curve_path, rows)

    with progress_from_args(args, remaining, 'train', 'epoch') as bar:
        trainer.run(remaining, progress=bar, callback=checkpoint)
    evaluation = {}
    if args.final_episodes:
        with progress_from_args(args, trainer.horizon, 'final evaluation', 'fixation') as bar:
            evaluation = evaluation_block(grid, fpoc, trainer.family.policy(trainer.params),
                                          args.final_episodes, args.final_seed,
                                          trainer.horizon, scene=trainer.config.scene(),
                                          progress=bar)
    save_policy(out, trainer.spec(evaluation=evaluation))
    write_curve(curve_path, rows)
    cfg = trainer.config
    task = fpoc.model if hasattr(fpoc, 'model') else f'count model {args.observation}'
    print(f'trained {cfg.family} {cfg.reward} policy on {grid.rows}x{grid.cols} '
          f'{task}: {trainer.epoch} epochs, lr {cfg.learning_rate}, '
          f'{trainer.wall_seconds:.1f} s of training'
          + ('' if prior_is_uniform(cfg.prior) else ', a prior that is not uniform'))
    if evaluation:
        f90, ci = evaluation['fixations_to_90'], evaluation['ci95']
        text = 'never' if f90 is None else f'{f90:.2f}'
        if ci:
            text += f' [{ci[0]:.2f}, {ci[1]:.2f}]'
        print(f'fixations to 90% correct (argmax, {counted(args.final_episodes, "episode")}, seed '
              f'{args.final_seed}): {text}')
        if evaluation.get('tracking_accuracy') is not None:
            ci = evaluation['tracking_accuracy_ci95']
            print(f"tracking accuracy {evaluation['tracking_accuracy']:.4f} "
                  f'[{ci[0]:.4f}, {ci[1]:.4f}]')
    print(f'ipomdp-gaze train: wrote {out} and {curve_path}', file=sys.stderr)
    return 0


def run_sweep(args, grid, model, config, params, init, out) -> int:
    """
    Train one policy per (seed, learning rate) on the executor; write each and the spread.

    Each training is one piece (its seed decides all its draws), so every file is the one a
    plain ``train --seed S --learning-rate LR`` writes, wherever it ran. Files are written here
    as the trainings finish: ``PATH-seedS[-lrLR].yaml`` and its ``.csv``.
    """
    from dataclasses import replace

    from ipomdp_gaze.drivers.pieces import train_piece
    from ipomdp_gaze.policies.policy_file import save_policy
    from ipomdp_gaze.policies.training import write_curve
    from ipomdp_gaze.simulation.executor import track
    import numpy as np
    seeds = args.seeds if args.seeds is not None else [config.seed]
    rates = args.learning_rates
    runs = [(seed, rate) for rate in (rates or [config.learning_rate]) for seed in seeds]
    paths = {(seed, rate): out.with_name(f'{out.stem}-seed{seed}'
                                         + (f'-lr{rate:g}' if rates else '') + '.yaml')
             for seed, rate in runs}
    for path in paths.values():         # refused before any training, as --out itself
        check_output_file('--out', path)
        check_output_file('--out', path.with_suffix('.csv'))
    epochs = args.epochs
    with executor_from_args(args, len(runs)) as executor, \
            progress_from_args(args, len(runs), 'train sweep', 'training') as bar:
        futures = {}
        for seed, rate in runs:
            run_config = replace(config, seed=seed, learning_rate=rate)
            futures[executor.submit(train_piece, grid, model, run_config, params, init, epochs,
                                    args.final_episodes, args.final_seed)] = (seed, rate)
        results = {}
        for future in track(list(futures), bar):
            seed, rate = futures[future]
            spec, rows, evaluation = future.result()
            path = paths[seed, rate]
            save_policy(path, spec)
            write_curve(path.with_suffix('.csv'), rows)
            results[seed, rate] = (path, rows, evaluation)
    print(f'{"file":<32} {"seed":>5} {"lr":>6} {"fix->90% (final)":>26} {"last curve":>10}')
    spread = {}
    for seed, rate in runs:
        path, rows, evaluation = results[seed, rate]
        f90 = evaluation.get('fixations_to_90')
        ci = evaluation.get('ci95')
        last = rows[-1]['fixations_to_90'] if rows else None
        final = '-' if not evaluation else 'never' if f90 is None else f'{f90:.2f}'
        if ci:
            final += f' [{ci[0]:.2f}, {ci[1]:.2f}]'
        curve = '-' if last is None else f'{last:.2f}'
        print(f'{path.name:<32} {seed:>5} {rate:>6g} {final:>26} {curve:>10}')
        value = f90 if evaluation else last
        if value is not None:
            spread.setdefault(rate, []).append(value)
    measure = (f'final evaluation ({counted(args.final_episodes, "episode")}, seed '
               f'{args.final_seed})'
               if args.final_episodes else 'last learning-curve point')
    for rate, values in spread.items():
        v = np.asarray(values, dtype=float)
        sd = f'{v.std(ddof=1):.2f}' if v.size > 1 else '-'
        print(f'lr {rate:g}: fixations to 90% by {measure} over {counted(v.size, "seed")}: mean '
              f'{v.mean():.2f}, sd {sd}, range {v.min():.2f} to {v.max():.2f}')
    return 0
