"""Fixation policies: baselines, learned families, training and shipped kernels."""
