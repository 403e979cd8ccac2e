# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
Run the benchmarks (``make bench``) and write ``docs/benchmarks.md`` with its figures.

Every ``bench/<group>/bench_*.py`` is one section of the report, found by name, so a new
benchmark (for example ``ros/bench_ros_loop.py``) only has to be dropped into a group folder
(``simulation``, ``ros``, ``faces``, ``pan_tilt``). A module takes part in
one of two ways:

- it defines ``bench(ctx) -> str``: markdown of its section, without the title. ``ctx`` is a
  :class:`Context` (``ctx.quick``, ``ctx.figure(name)`` for a path in the report's ``figures/``
  folder, ``ctx.log(text)``). Optional module attributes: ``TITLE`` (the section heading) and
  ``ORDER`` (position; lower first, default 50);
- otherwise it is run as a script (``python bench/<group>/bench_x.py``, and ``--quick`` when the
  run is quick: a script benchmark must accept it) and its standard output is quoted; its
  standard error (progress lines) goes to the console, and into the section only when the
  script fails.

Sections are delimited by ``<!-- bench:NAME order=N -->`` markers, so ``--only NAME`` re-runs one
benchmark and keeps the others' last results in the file. The soak of the face loop
(``bench/ros/soak_face_loop.py``, section ``soak_face_loop``) is not one of these benchmarks: it
runs for minutes, under ``make soak`` only, which writes its section; a full run keeps that
section as it was. A benchmark that fails (an exception,
a script's non-zero exit status) gets its error as its section; the others are still written,
then the run exits with status 1 and names the failed ones. Timings are not tests: nothing in
``make test`` depends on them.

Figures go to ``docs/figures/`` when the report is ``docs/benchmarks.md``, otherwise to
``figures/`` beside the ``--out`` file (the report links them as ``figures/NAME``).

Usage: ``.venv/bin/python bench/run.py [--only latency,simulate] [--quick] [--out FILE]``.
"""
import argparse
import datetime
import importlib.util
import os
from pathlib import Path
import platform
import re
import subprocess
import sys
import threading
import time
import traceback

# One BLAS thread, set before any benchmark imports numpy: on a small shared machine a
# multi-threaded matrix-vector product waits for a busy core and becomes 10-100x slower; the
# controller runs single-threaded as well.
for _name in ('OPENBLAS_NUM_THREADS', 'OMP_NUM_THREADS', 'MKL_NUM_THREADS'):
    os.environ.setdefault(_name, '1')

BENCH_DIR = Path(__file__).resolve().parent
ROOT = BENCH_DIR.parent
DEFAULT_OUT = ROOT / 'docs' / 'benchmarks.md'
FIGURES = ROOT / 'docs' / 'figures'
SCRIPT_TIMEOUT_S = 3600
# Last lines of a failed script's standard error quoted in its section.
ERROR_LINES = 40
# Sections another command writes (not bench_*.py): a full run keeps them as they are.
OTHER_SECTIONS = {'soak_face_loop': '`make soak` (bench/ros/soak_face_loop.py)'}
MARK = re.compile(r'<!-- bench:(\w+) order=([-\d.]+) -->\n(.*?)<!-- /bench:\1 -->\n', re.S)


class Context:
    """What a benchmark's ``bench(ctx)`` gets: the run's options and where to put figures."""

    def __init__(self, quick: bool, figures: Path):
        self.quick = quick
        self.figures = figures

    def figure(self, name: str) -> Path:
        """Path of a figure file ``<figures>/<name>`` (the directory is created)."""
        self.figures.mkdir(parents=True, exist_ok=True)
        return self.figures / name

    def log(self, text: str) -> None:
        """Progress line on stderr (kept out of the report)."""
        print(text, file=sys.stderr, flush=True)


def discover() -> dict:
    """Map benchmark name (``bench_NAME.py``) to its path."""
    return {p.stem[len('bench_'):]: p for p in sorted(BENCH_DIR.rglob('bench_*.py'))}


def load(path: Path):
    """Import a benchmark module from its path."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    spec = importlib.util.spec_from_file_location(f'bench_modules.{path.stem}', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_script(path: Path, quick: bool) -> tuple[int, str, str]:
    """
    Run a script benchmark; return ``(exit status, stdout, stderr)``.

    ``quick``: the script gets ``--quick``. Its standard error is echoed to ours as it comes
    (progress lines); a script that runs past :data:`SCRIPT_TIMEOUT_S` is killed.
    """
    command = [sys.executable, str(path)] + (['--quick'] if quick else [])
    proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    out, err = [], []

    def read_out():
        out.append(proc.stdout.read())

    def read_err():
        for line in proc.stderr:
            err.append(line)
            sys.stderr.write(line)
            sys.stderr.flush()

    readers = [threading.Thread(target=read_out, daemon=True),
               threading.Thread(target=read_err, daemon=True)]
    for reader in readers:
        reader.start()
    try:
        status = proc.wait(timeout=SCRIPT_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        status = proc.wait()
        err.append(f'killed after {SCRIPT_TIMEOUT_S} s\n')
    for reader in readers:
        reader.join()
    return status, ''.join(out), ''.join(err)


def run_one(name: str, path: Path, ctx: Context) -> tuple[float, str, str, bool]:
    """Run one benchmark; return ``(order, title, markdown body, whether it succeeded)``."""
    module = load(path)
    title = getattr(module, 'TITLE', name.replace('_', ' ').capitalize())
    order = float(getattr(module, 'ORDER', 50))
    t0 = time.perf_counter()
    if hasattr(module, 'bench'):
        try:
            body, ok = module.bench(ctx).rstrip() + '\n', True
        except Exception:                # the section shows it; the run goes on, then fails
            error = traceback.format_exc().strip()
            ctx.log(error)
            body, ok = f'Failed:\n\n```\n{error}\n```\n', False
    else:
        status, out, err = run_script(path, ctx.quick)
        ok = status == 0
        text = out.strip()
        if not ok:                       # progress lines stay out unless they tell why
            text = '\n'.join([text] + err.strip().splitlines()[-ERROR_LINES:]).strip()
        note = '' if ok else f' (exit status {status})'
        shown = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
        command = f"python {shown.as_posix()}{' --quick' if ctx.quick else ''}"
        body = f'Output of `{command}`{note}:\n\n```\n{text}\n```\n'
    wall = time.perf_counter() - t0
    body += f'\n*Measured {machine()}; this section took {wall:.0f} s.*\n'
    return order, title, body, ok


def machine() -> str:
    """One line on the machine and software a section was measured on."""
    import numpy
    import scipy
    load_avg = ', '.join(f'{x:.1f}' for x in os.getloadavg())
    return (f'{datetime.datetime.now().isoformat(timespec="minutes")} on `{platform.node()}` '
            f'({platform.machine()}, {os.cpu_count()} CPUs, load average {load_avg}), '
            f'Python {platform.python_version()}, numpy {numpy.__version__}, '
            f'scipy {scipy.__version__}, OPENBLAS_NUM_THREADS='
            f'{os.environ.get("OPENBLAS_NUM_THREADS", "unset")}')


# Benchmarks issue 5 asks for that other engineers add later: listed as pending until they exist.
PENDING = {
    'ros_loop': 'ROS loop: camera evidence -> controller -> pan_tilt -> camera as separate '
                'processes, round trip and fixations per second (issue 5 item 2)',
    'training': "training time to the learning issue's target (issue 5 item 3)",
}

HEADER = """# Benchmarks

Written by `make bench` (`bench/run.py`): one section per `bench/<group>/bench_*.py`, and the
soak of the face loop, which only `make soak` runs and writes (`make bench` keeps its section).
The machine is small and shared (other engineers' jobs run at the same time), so absolute times
move by 2x or more from run to run; every timing is therefore shown beside a reference measured
in the same run, and the ratios are the numbers to compare. Benchmarks are not tests: nothing in
`make test` depends on timing.

"""


def compose(sections: dict, order: dict, titles: dict) -> str:
    """Assemble the report from sections ``{name: body}``."""
    names = sorted(sections, key=lambda n: (order.get(n, 50.0), n))
    text = HEADER
    pending = [f'- `bench/bench_{n}.py`: {what}' for n, what in PENDING.items()
               if n not in discover()]
    if pending:
        text += 'Not measured yet (each drops in as one file):\n\n' + '\n'.join(pending) + '\n\n'
    for name in names:
        text += (f'<!-- bench:{name} order={order.get(name, 50.0):g} -->\n## {titles[name]}\n\n'
                 f'{sections[name]}<!-- /bench:{name} -->\n')
    return text


def previous(path: Path) -> tuple[dict, dict, dict]:
    """Sections, titles and positions already in the report (kept by ``--only``)."""
    if not path.exists():
        return {}, {}, {}
    sections, titles, order = {}, {}, {}
    for match in MARK.finditer(path.read_text()):
        name, position, block = match.group(1), match.group(2), match.group(3)
        heading, _, body = block.partition('\n\n')
        sections[name] = body
        titles[name] = heading.removeprefix('## ').strip()
        order[name] = float(position)
    return sections, titles, order


def figures_for(out: Path) -> Path:
    """Where a report's figures go: ``docs/figures`` for ``docs/benchmarks.md``, else beside it."""
    out = out.resolve()
    return FIGURES if out == DEFAULT_OUT else out.parent / 'figures'


def main(argv=None) -> int:
    """Run the selected benchmarks and write the report; 1 if a benchmark failed."""
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[1],
        epilog='The soak of the face loop (section soak_face_loop) runs under make soak only; a '
               'full run keeps its section. A benchmark that fails is written as its section '
               'and the run exits with status 1.')
    parser.add_argument('--only', default='', help='comma-separated names (bench_NAME.py)')
    parser.add_argument('--quick', action='store_true',
                        help='few calls: a smoke run (script benchmarks get --quick)')
    parser.add_argument('--out', type=Path, default=DEFAULT_OUT,
                        help='report path (default docs/benchmarks.md); its figures go to '
                             'figures/ beside it')
    args = parser.parse_args(argv)
    found = discover()
    names = [n for n in args.only.split(',') if n] or list(found)
    unknown = [n for n in names if n not in found]
    if unknown:
        if unknown[0] in OTHER_SECTIONS:
            parser.error(f'{unknown[0]!r} is not a benchmark of this runner: '
                         f'{OTHER_SECTIONS[unknown[0]]} writes its section')
        parser.error(f"unknown benchmark {unknown[0]!r}; available: {', '.join(found)}")
    figures = figures_for(args.out)
    if figures == FIGURES and args.out.resolve() != DEFAULT_OUT:
        parser.error(f'--out {args.out}: its figures would replace those of '
                     f'{DEFAULT_OUT.relative_to(ROOT)} in docs/figures; write it elsewhere')
    ctx = Context(args.quick, figures)
    sections, titles, order = previous(args.out)
    if not args.only:                    # a full run writes every section anew but the soak's
        for kept in (sections, titles, order):
            for name in set(kept) - set(OTHER_SECTIONS):
                del kept[name]
    failed = []
    for name in names:
        ctx.log(f'== bench_{name}')
        position, title, body, ok = run_one(name, found[name], ctx)
        sections[name], titles[name], order[name] = body, title, position
        if not ok:
            failed.append(name)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(compose(sections, order, titles))
    ctx.log(f'wrote {args.out}')
    if failed:
        ctx.log(f"failed: {', '.join(failed)} (each section shows its error)")
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
