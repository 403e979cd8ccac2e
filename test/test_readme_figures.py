# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Every figure README.md shows is drawn by the command its caption names (issue 35, item 3).

Each ``![...](docs/figures/NAME.png)`` of the README must have one caption command, a backticked
``ipomdp-gaze ... --plot docs/figures/NAME.png``; ``make figures`` must run exactly those
commands; and each command, run here with its plot sent to a temporary file, must still draw a
PNG of the committed figure's size (within 2 px). The demos' commands (over real DDS) run in
test_ros_faces.py, whose tests check the same runs.
"""
from pathlib import Path
import re
import subprocess
import sys

import cv2
import pytest

ROOT = Path(__file__).resolve().parents[1]
FIGURE = re.compile(r'!\[[^\]]*\]\((docs/figures/[\w.-]+\.png)\)')
COMMAND = re.compile(r'`(ipomdp-gaze [^`]*?--plot\s+(docs/figures/[\w.-]+\.png))`')


def readme_figures() -> dict:
    """Return ``{figure path: caption command}`` (whitespace in a command made single)."""
    text = (ROOT / 'README.md').read_text()
    commands = {}
    for match in COMMAND.finditer(text):
        commands.setdefault(match.group(2), []).append(' '.join(match.group(1).split()))
    return {figure: commands.get(figure, []) for figure in FIGURE.findall(text)}


def make_figures_commands() -> list:
    """Return the commands of the Makefile's ``figures`` target, as a user would type them."""
    lines = (ROOT / 'Makefile').read_text().split('\nfigures:', 1)[1].split('\n\n', 1)[0]
    return [line.strip().replace('$(VENV)/bin/ipomdp-gaze', 'ipomdp-gaze')
            for line in lines.splitlines()[1:] if line.startswith('\t')]


def test_every_readme_figure_has_one_command_and_make_figures_runs_them():
    figures = readme_figures()
    assert figures, 'README.md shows no figure'
    for figure, commands in figures.items():
        assert len(commands) == 1, f'{figure}: caption commands {commands}'
    assert sorted(make_figures_commands()) == sorted(c[0] for c in figures.values())


def _params():
    """Return the figures whose commands run here: all but the demos' (test_ros_faces.py)."""
    return [pytest.param(figure, commands[0] if commands else '', id=Path(figure).stem)
            for figure, commands in sorted(readme_figures().items())
            if not (commands and commands[0].split()[1:2] == ['demo'])]


def test_every_demo_figure_command_is_checked_with_the_face_demos():
    from test_ros_faces import DEMO_FIGURES
    demos = {f for f, c in readme_figures().items() if c and c[0].split()[1:2] == ['demo']}
    assert demos and sorted(demos) == sorted(DEMO_FIGURES.values())


@pytest.mark.parametrize('figure, command', _params())
def test_a_readme_figure_command_still_draws_it(figure, command, tmp_path):
    out = tmp_path / Path(figure).name
    argv = command.replace(figure, str(out)).split()[1:]
    done = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', *argv], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    drawn, shipped = cv2.imread(str(out)), cv2.imread(str(ROOT / figure))
    assert drawn is not None, f'{command} drew nothing at {out}'
    # matplotlib 3.7's tight bounding box is a pixel smaller (505 rows, not 506)
    assert drawn.shape[2:] == shipped.shape[2:] and \
        all(abs(a - b) <= 2 for a, b in zip(drawn.shape[:2], shipped.shape[:2])), \
        (drawn.shape, shipped.shape)
