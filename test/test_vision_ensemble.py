# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""The ensemble detector (several detectors as one) and YuNet on an upscaled image."""
import cv2
from ipomdp_gaze.vision.detector import (as_detections, detector_settings, group_boxes,
                                         HaarDetector, REFERENCE_CASCADE)
from ipomdp_gaze.vision.detectors import detector_from_settings, make_detector, parse_options
import numpy as np
import pytest
from skimage import data

PROFILE = 'haarcascade_profileface.xml'


@pytest.fixture(scope='module')
def astronaut():
    return data.astronaut()


def test_an_ensemble_returns_each_members_boxes_repeated_by_its_weight(astronaut):
    members = [{'kind': 'haar'}, {'kind': 'haar', 'cascade': PROFILE, 'weight': 3}]
    ensemble = make_detector('ensemble', members=members)
    assert ensemble.color == 'gray' and ensemble.window_px == (20, 20)
    gray = cv2.cvtColor(astronaut, cv2.COLOR_RGB2GRAY)
    frontal = HaarDetector()(gray)
    profile = HaarDetector(PROFILE)(gray)
    assert len(frontal) and len(profile)
    boxes, scores = as_detections(ensemble(gray))
    expected = np.concatenate([frontal, np.repeat(profile, 3, axis=0)])
    assert np.array_equal(boxes, expected) and np.all(scores == 1.0)
    # An RGB image is turned grey for a grey member, as the member's own input would be.
    assert np.array_equal(ensemble(astronaut)[:, :4], expected)
    # A box of weight 3 is 3 neighbours of itself when grouped.
    grouped = ensemble.group(np.repeat(profile[:1], 3, axis=0), 2)
    assert np.array_equal(grouped, group_boxes(np.repeat(profile[:1], 3, axis=0), 2))
    assert len(grouped) == 1


def test_an_ensemble_is_recorded_member_by_member_and_rebuilt_with_their_checks():
    members = [{'kind': 'haar', 'cascade': [REFERENCE_CASCADE, PROFILE],
                'mirror': [False, True]}, {'kind': 'haar', 'weight': 2}]
    ensemble = make_detector('ensemble', members=members)
    settings = detector_settings(ensemble)
    assert settings['kind'] == 'ensemble' and settings['opencv'] == cv2.__version__
    recorded = settings['members']
    assert [m['weight'] for m in recorded] == [1, 2]
    assert recorded[0]['cascade'] == [REFERENCE_CASCADE, PROFILE]
    assert all('opencv' not in m and 'window_px' not in m for m in recorded)
    assert [len(sha) for sha in recorded[0]['cascade_sha256']] == [64, 64]
    assert len(recorded[1]['cascade_sha256']) == 64
    assert detector_settings(detector_from_settings(settings)) == settings
    wrong = {**settings, 'members': [recorded[0], {**recorded[1], 'cascade_sha256': '0' * 64}]}
    with pytest.raises(ValueError, match='ensemble member 1: the installed cascade .* differs'):
        detector_from_settings(wrong)
    heavier = {**settings, 'members': [recorded[0], {**recorded[1], 'weight': 3}]}
    assert detector_settings(detector_from_settings(heavier))['members'][1]['weight'] == 3


def test_an_ensemble_is_given_on_the_command_line_as_yaml():
    options = parse_options(['members=[{kind: haar}, {kind: haar, cascade: '
                             'haarcascade_profileface.xml, weight: 2}]'])
    ensemble = make_detector('ensemble', **options)
    assert ensemble.weights == [1, 2]
    assert ensemble.members[1].cascade_name == PROFILE


@pytest.mark.parametrize('members, reason', [
    ([], 'non-empty list'),
    ({'kind': 'haar'}, 'non-empty list'),
    (['haar'], 'member 0 must be a mapping'),
    ([{'weight': 2}], 'member 0 needs a kind'),
    ([{'kind': 'haar'}, {'kind': 'haar', 'weight': 0}], r'member 1: weight must be an int'),
    ([{'kind': 'haar', 'weight': True}], 'weight must be an int'),
    ([{'kind': 'haar', 'weight': 1.5}], 'weight must be an int'),
    ([{'kind': 'ensemble', 'members': [{'kind': 'haar'}]}], 'cannot hold an ensemble'),
    ([{'kind': 'nope'}], "member 0: unknown detector 'nope'"),
    ([{'kind': 'haar', 'scale_factor': 0.5}], 'member 0: scale_factor must be'),
])
def test_an_ensemble_refuses_bad_members_naming_the_member(members, reason):
    with pytest.raises(ValueError, match=reason):
        make_detector('ensemble', members=members)


def test_yunet_upscaled_is_yunet_on_the_resized_image_with_boxes_mapped_back(astronaut):
    small = cv2.resize(astronaut, (160, 160), interpolation=cv2.INTER_AREA)
    plain = make_detector('yunet', score_threshold=0.3)
    twice = make_detector('yunet', score_threshold=0.3, upscale=2)
    resized = cv2.resize(small, (320, 320), interpolation=cv2.INTER_CUBIC)
    expected = plain(resized)
    expected[:, :4] /= 2.0
    got = twice(small)
    assert len(got) and np.allclose(got, expected[np.lexsort((expected[:, 1], expected[:, 0],
                                                              -expected[:, 4]))])
    settings = detector_settings(twice)
    assert settings['upscale'] == 2.0 and 'upscale' not in detector_settings(plain)
    assert detector_settings(detector_from_settings(settings)) == settings
    assert 'upscale=2' in repr(twice)
    for bad in (0.5, 9, float('nan'), True, '2'):
        with pytest.raises(ValueError, match=r'upscale must be a number in \[1, 8\]'):
            make_detector('yunet', upscale=bad)


def test_an_ensemble_of_haar_and_yunet_takes_rgb_and_records_both():
    members = [{'kind': 'haar'}, {'kind': 'yunet', 'upscale': 2, 'weight': 5}]
    ensemble = make_detector('ensemble', members=members)
    assert ensemble.color == 'rgb'
    image = data.astronaut()
    yunet = ensemble.members[1](image)
    assert len(yunet)
    out = ensemble(image)
    assert np.array_equal(out[-5 * len(yunet):], np.repeat(yunet, 5, axis=0))
    settings = detector_settings(ensemble)
    assert settings['members'][1]['upscale'] == 2.0 and settings['members'][1]['weight'] == 5
    assert detector_settings(detector_from_settings(settings)) == settings
