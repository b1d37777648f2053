"""Experiments on the walking robot: scripted walks, trajectory extraction and comparison (Table 5), the
prototype run, statistics and videos (the figures are drawn from their saved results by `plots/`), and
`parallel`, the one process pool for independent walks.
May import every layer above it; never the sweeps (the orchestration on top of the package)."""
