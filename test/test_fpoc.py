# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""FPOC values against docs/design.md section 2 and their parameter checks."""
from ipomdp_gaze.model.fpoc import (CameraFPOC, dprime_matrix, dprime_table, fpoc_from_dict,
                                    HumanFPOC, make_fpoc)
from ipomdp_gaze.model.grid import Grid
import numpy as np
import pytest


def test_human_default_matches_design_table():
    expected = [2.000, 1.953, 1.579, 1.162, 0.800, 0.520, 0.321]
    got = HumanFPOC().of_eccentricity(0.42 * np.arange(7))
    np.testing.assert_allclose(got, expected, atol=1e-3)


def test_human_is_radial_and_uses_offsets():
    f = make_fpoc('human')
    assert f(0.42 * 3, 0.42 * 4) == pytest.approx(f.of_eccentricity(0.42 * 5))
    assert f(0.0, 0.0) == pytest.approx(2.0)


def test_human_foveal_dprime_parameter():
    assert make_fpoc('human', foveal_dprime=3.0)(0, 0) == pytest.approx(3.0)
    # More external noise makes the fall-off flatter (the noise term grows slower with e).
    assert make_fpoc('human', noise_contrast=0.4).of_eccentricity(1.0) > HumanFPOC()(1.0, 0)


def test_human_foveal_dprime_is_met_up_to_the_top_of_its_range():
    """Past d0 = 11.9, 2 - 2 Phi(d0 / sqrt 2) rounded to 0: a math domain error (QA)."""
    for d0 in (5.9, 6.1, 8.0, 11.5, 11.95, 12.0):
        assert make_fpoc('human', foveal_dprime=d0)(0, 0) == pytest.approx(d0, rel=1e-9)
    # the formula's own shape, documented: above threshold d' peaks off the fixation
    ecc = np.linspace(0, 2, 2001)
    values = make_fpoc('human', foveal_dprime=3.0).of_eccentricity(ecc)
    assert values.max() == pytest.approx(3.53, abs=0.01) and ecc[values.argmax()] > 0.3


@pytest.mark.filterwarnings('error')
def test_human_is_zero_at_any_far_eccentricity():
    """
    From about 6e307 degrees 2.8 e overflowed: d' was NaN, with a warning (QA).

    ``search --spacing-deg 1e308`` then failed on an ELM "kernel" of NaN, and evaluate scored
    every search wrong without a word; an offset past the largest double is infinitely far.
    """
    far = np.array([1e3, 6e307, 1e308, np.finfo(float).max, np.inf])
    np.testing.assert_array_equal(HumanFPOC().of_eccentricity(far), 0.0)
    grid = Grid(3, 3, 1e308)
    table = dprime_table(grid, HumanFPOC())
    assert table[2, 2] == pytest.approx(2.0)
    np.testing.assert_array_equal(np.delete(table.ravel(), 12), 0.0)
    assert grid.offsets_deg(0)[0][2] == np.inf         # two columns of 1e308 degrees


def test_exponential():
    f = make_fpoc('exponential')
    assert f(1.5, 0) == pytest.approx(2.0 * np.exp(-1))
    assert f(0, 0) == 2.0


def test_camera_rectangle_edge_is_inside():
    grid = Grid(11, 11, 0.42)
    d = dprime_table(grid, make_fpoc('camera'))
    # Default half-width 0.84 deg = 2 cells: a 5x5 block of 4.0 around the centre of the table.
    inside = np.zeros_like(d, dtype=bool)
    inside[10 - 2:10 + 3, 10 - 2:10 + 3] = True
    np.testing.assert_array_equal(d, np.where(inside, 4.0, 0.0))


def test_camera_edge_with_rounding_and_circle():
    cam = CameraFPOC(dprime=3.0, half_width_deg=0.3 * 3, half_height_deg=0.1)
    assert cam(0.1 + 0.2 * 4, 0.1) == 3.0         # 0.9000000000000001 > 0.9: still inside
    assert cam(0.91, 0.0) == 0.0
    circle = make_fpoc('camera', shape='circle', radius_deg=1.0)
    assert circle(0.6, 0.8) == 4.0 and circle(0.71, 0.71) == 0.0
    assert circle.to_dict() == {'model': 'camera', 'dprime': 4.0, 'shape': 'circle',
                                'radius_deg': 1.0}


def test_table_interpolates_and_is_constant_beyond():
    f = make_fpoc('table', ecc_deg=[0.5, 1.5], dprime=[3.0, 1.0])
    np.testing.assert_allclose(f.of_eccentricity([0.0, 0.5, 1.0, 1.5, 9.0]),
                               [3.0, 3.0, 2.0, 1.0, 1.0])


@pytest.mark.parametrize('model, params, message', [
    ('human', {'foveal_dprime': 0}, 'foveal_dprime'),
    ('human', {'noise_contrast': float('nan')}, 'noise_contrast'),
    ('human', {'bogus': 1}, "unknown parameter 'bogus'"),
    ('camera', {'shape': 'hexagon'}, 'shape must be one of'),
    ('table', {'ecc_deg': [0, 1], 'dprime': [1]}, 'equal length'),
    ('table', {'dprime': [2, 1, 0]}, r'got 2 ecc_deg \[0.0, 1.0\] and 3 dprime \[2.0, 1.0, 0.0\] '
     r'\(a value not given is its default: ecc_deg \[0.0, 1.0\]'),
    ('table', {'ecc_deg': [1, 0], 'dprime': [1, 1]}, 'increasing'),
    ('table', {'ecc_deg': [0, 1], 'dprime': [1, -1]}, '>= 0'),
    ('nope', {}, 'valid models: human, exponential, camera, table'),
])
def test_invalid_parameters_name_the_problem(model, params, message):
    with pytest.raises(ValueError, match=message):
        make_fpoc(model, **params)


def test_dprime_matrix_agrees_with_offsets():
    grid = Grid(3, 4, 0.5)
    f = make_fpoc('exponential')
    d = dprime_matrix(grid, f)
    for k in range(grid.n_cells):
        dx, dy = grid.offsets_deg(k)
        np.testing.assert_allclose(d[:, k], f(dx, dy))


def test_round_trip_through_dict():
    for f in (make_fpoc('human', foveal_dprime=2.5), make_fpoc('camera', half_width_deg=1.0),
              make_fpoc('table', ecc_deg=[0, 2], dprime=[2, 0])):
        assert fpoc_from_dict(f.to_dict()) == f
