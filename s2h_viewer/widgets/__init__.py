"""Reusable Qt widgets (the only core-importing Qt code besides app/): viewports, timeline, heatmap."""
