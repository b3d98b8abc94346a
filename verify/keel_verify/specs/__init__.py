"""``keel-verify specs``: model-check Keel's TLA+ protocol specifications with TLC.

The specs live in ``spec/`` (Heartbeat, MasterElection, ConfigSwitch), each with model
wrappers (``MC*.tla`` + ``.cfg``); ``spec/mutants/`` holds deliberately broken variants
that TLC must reject. ``spec/manifest.json`` lists every model and mutant with its
expected outcome and, for models, the distinct-state count CI compares against.

Modules: :mod:`.tlc` runs TLC and reads its verdict, :mod:`.counterexample` turns TLC's
error trace into a table of changed variables, :mod:`.manifest` reads the manifest,
:mod:`.mission_models` instantiates the models from a mission file, :mod:`.cli` is the
command.
"""
