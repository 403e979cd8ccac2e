# Copyright 2026 ipomdp_gaze developers
# SPDX-License-Identifier: Apache-2.0
"""What a cell's observation is: counts, the best score in bins, counts above a threshold."""
from ipomdp_gaze.files.observation_file import (load_observation, model_from_dict, model_to_dict,
                                                ObservationFileError, save_observation)
from ipomdp_gaze.model.cell_observation import cell_observation_of, CellObservation, quantile_edges
from ipomdp_gaze.vision.calibrate import best_scores, choose_edges, Tallies
from ipomdp_gaze.vision.fovea import Fovea, FoveaConfig
from ipomdp_gaze.vision.search import check_model
import numpy as np
import pytest

CELLS = np.array([0, 0, 0, 2, 2, 3])
SCORES = np.array([0.2, 0.9, 0.5, 0.6, 0.61, 0.1])


def test_each_kind_turns_detections_into_the_documented_integers():
    counts = CellObservation('counts', 3)
    np.testing.assert_array_equal(counts.values(CELLS, SCORES, 5), [2, 0, 2, 1, 0])
    above = CellObservation('threshold', 4, threshold=0.55)
    np.testing.assert_array_equal(above.values(CELLS, SCORES, 5), [1, 0, 2, 0, 0])
    bins = CellObservation('score_bins', 4, edges=(0.3, 0.7))
    # best scores: cell 0 0.9 -> bin 3, cell 2 0.61 -> bin 2, cell 3 0.1 -> bin 1, none -> 0
    np.testing.assert_array_equal(bins.values(CELLS, SCORES, 5), [3, 0, 2, 1, 0])
    # A score exactly on an edge goes to the upper bin.
    np.testing.assert_array_equal(bins.values([1], [0.7], 2), [0, 3])


@pytest.mark.parametrize('kwargs, words', [
    ({'kind': 'best'}, 'kind must be one of counts, score_bins, threshold'),
    ({'max_count': 1}, 'max_count must be an int >= 2'),
    ({'kind': 'score_bins', 'max_count': 4, 'edges': (0.5,)}, 'needs 2 edges, got 1'),
    ({'kind': 'score_bins', 'max_count': 4, 'edges': (0.5, 0.5)}, 'strictly increasing'),
    ({'kind': 'counts', 'edges': (0.5,)}, 'edges are for score_bins'),
    ({'kind': 'threshold', 'threshold': float('nan')}, 'threshold must be a finite'),
])
def test_bad_rules_are_refused_naming_the_problem(kwargs, words):
    with pytest.raises(ValueError, match=words):
        CellObservation(**kwargs)


def test_rules_round_trip_and_an_unknown_key_is_refused():
    for rule in (CellObservation(), CellObservation('threshold', 5, threshold=0.4),
                 CellObservation('score_bins', 4, edges=(0.25, 0.75))):
        assert CellObservation.from_dict(rule.to_dict()) == rule
    with pytest.raises(ValueError, match="unknown cell observation setting 'bins'"):
        CellObservation.from_dict({'kind': 'counts', 'bins': 3})
    assert cell_observation_of({}, 7) == CellObservation('counts', 7)
    with pytest.raises(ValueError, match='K = 4 but its tables have K = 7'):
        cell_observation_of({'cells': {'kind': 'counts', 'max_count': 4}}, 7)


def test_edges_share_the_training_scores_out_and_merge_ties():
    scores = np.linspace(0.5, 1.0, 101)
    edges = quantile_edges(scores, 4)
    assert len(edges) == 3 and np.all(np.diff(edges) > 0)
    bins = CellObservation('score_bins', 5, edges).values(np.arange(101), scores, 101)
    share = np.bincount(bins, minlength=5)[1:] / 101
    assert np.all(np.abs(share - 0.25) < 0.02)
    # A detector with one score (Haar: every box scores 1) leaves one bin, 'any box': K = 2.
    rule = choose_edges(Tallies(None, None, None, None, scores=np.ones(50)), 10)
    assert rule.max_count == 2 and rule.edges == ()
    with pytest.raises(ValueError, match='no score to choose bin edges from'):
        quantile_edges([], 4)


def test_best_scores_keeps_one_score_per_observed_cell():
    np.testing.assert_array_equal(best_scores(CELLS, SCORES), [0.9, 0.61, 0.1])
    observed = np.array([False, True, True, True, True])
    np.testing.assert_array_equal(best_scores(CELLS, SCORES, observed), [0.61, 0.1])
    assert best_scores([], []).size == 0


class ScoredBlob:
    """Boxes with scores, always the same (an RGB detector)."""

    color = 'rgb'

    def __call__(self, rgb):
        return np.array([[10.0, 10.0, 8.0, 8.0, 0.9], [40.0, 40.0, 8.0, 8.0, 0.3]])

    def settings(self):
        return {'kind': 'test:ScoredBlob'}


def test_the_fovea_observes_best_scores_in_bins_and_the_file_records_the_rule(tmp_path):
    from ipomdp_gaze.model.observation import CountObservation
    rule = CellObservation('score_bins', 4, edges=(0.5, 0.8))
    config = FoveaConfig(windows_cells=(6,), max_count=4)      # the whole image, full size
    fovea = Fovea(ScoredBlob(), (6, 6), config, cells=rule)
    fovea.start(np.zeros((60, 60), np.uint8))               # grey in, the detector gets RGB
    counts = fovea.observe(0).counts
    assert counts[1 * 6 + 1] == 3 and counts[4 * 6 + 4] == 1 and np.nansum(counts) == 4
    table = np.full((6, 6, 4), 0.25)
    model = CountObservation(fovea.grid, table, table, {'cells': rule.to_dict(),
                                                        'fovea': config.to_dict()})
    path = save_observation(tmp_path / 'm.yaml', model)
    loaded = load_observation(path)
    assert cell_observation_of(loaded.meta, 4) == rule
    check_model(loaded, fovea)
    with pytest.raises(ValueError, match='records cells'):
        check_model(loaded, Fovea(ScoredBlob(), (6, 6), config))
    doc = model_to_dict(model)
    doc['cells'] = {'kind': 'score_bins', 'max_count': 4, 'edges': [0.8, 0.5]}
    with pytest.raises(ObservationFileError, match='cells: edges must be finite and strictly'):
        model_from_dict(doc)
    with pytest.raises(ValueError, match=r'K = max_count \(4\)'):
        Fovea(ScoredBlob(), (6, 6), config, cells=CellObservation('counts', 5))
