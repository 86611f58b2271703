"""Slip detectors (L2): signal models, force / tactile / combined detectors, evaluation."""
