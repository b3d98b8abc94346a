"""Trace validation: is what a running node did a behaviour of the TLA+ specs?

``keel-verify trace`` reads the NDJSON traces of ``keel-sim`` and ``keel-node``
(docs/verification.md, spec/NAMES.md), turns the lines of each protocol into a TLA+ trace module
and lets TLC decide whether the protocol's spec has a behaviour that explains them, line
by line (spec/README.md, "Trace validation").
"""
