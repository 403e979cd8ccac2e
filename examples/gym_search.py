# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Drive the Gymnasium environment with a shipped kernel and with a baseline.

Run: ``.venv/bin/python examples/gym_search.py``. Each policy sees the belief the environment
returns and picks the next fixation; an episode ends when the most likely cell reaches the
confidence threshold. Prints fixations per episode and how often the final guess is right.
"""
import gymnasium
from ipomdp_gaze.policies.baselines import make_baseline
from ipomdp_gaze.policies.policy_file import load_policy_spec
import ipomdp_gaze.simulation.gym  # noqa: F401  (registers ipomdp_gaze/VisualSearch-v0)
import numpy as np


def run(policy, env, episodes: int, seed: int) -> tuple[float, float]:
    """Return (mean fixations, fraction right) of ``policy`` over ``episodes`` searches."""
    rng = np.random.default_rng(seed)
    steps, right = [], 0
    for episode in range(episodes):
        obs, info = env.reset(seed=seed + episode)
        for t in range(env.unwrapped.max_steps):
            belief = obs['belief'].reshape(1, -1)
            action = int(policy.select(belief, t, rng)[0])
            obs, reward, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        steps.append(t + 1)
        right += info['map_cell'] == info['target']
    return float(np.mean(steps)), right / episodes


def main(episodes: int = 200, seed: int = 0) -> dict:
    """Compare the shipped human-7x7-infomax kernel with ELM and MAP on the same seeds."""
    spec = load_policy_spec('human-7x7-infomax')
    env = gymnasium.make('ipomdp_gaze/VisualSearch-v0', rows=spec.grid.rows, cols=spec.grid.cols,
                         spacing_deg=spec.grid.spacing_deg, fpoc=spec.fpoc, confidence=0.95)
    policies = {'human-7x7-infomax (shipped kernel)': spec.make_policy('argmax'),
                'elm': make_baseline('elm', spec.grid, spec.fpoc),
                'map': make_baseline('map', spec.grid, spec.fpoc)}
    results = {}
    for name, policy in policies.items():
        results[name] = run(policy, env, episodes, seed)
        mean_steps, right = results[name]
        print(f'{name:36s} {mean_steps:5.2f} fixations to 95% confidence, right {right:.1%}')
    return results


if __name__ == '__main__':
    main()
