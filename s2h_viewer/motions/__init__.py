"""Gesture library, per-hand contact fitting and motion synthesis."""
