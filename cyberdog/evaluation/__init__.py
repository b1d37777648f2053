"""The `evaluate.py` command line over the analysis layer: `cli` (one sub-parser per sub-command, no heavy
imports), `learned` (the learned trajectories: loaded, or extracted from policies), `parts` (comparison,
prototype, figures, video) and `commands` (one function per sub-command). Nothing is imported here, so that
`evaluate.py --help` loads only `cli`."""
