"""Qualitative posture features: poses, skeletons, geometry, fluents and QMPs."""
