"""The `evaluate.py` command line over the analysis layer. Imports go one way, down this list: `cli` (assembles
the parser, no heavy imports) over `parsers` (each sub-command's options) over `options` (the usage error, value
checks and shared option blocks, imported by every module here); `commands` (one function per sub-command) over
`check`, `pd_match` and `export` (three sub-commands, options included), `parts` (comparison, prototype, figures,
video), `extraction` (learned paths from policies) over `learned` (learned paths loaded), and `output` (a run's
output folder) and `recorded_trot`. Nothing is imported here, so that `evaluate.py --help` loads only `cli` and what it
needs."""
