"""Experiments on the walking robot: scripted walks, trajectory extraction and comparison (Table 5), the
prototype run, across-seed aggregation, statistics, figures and videos. May import every layer above it."""
