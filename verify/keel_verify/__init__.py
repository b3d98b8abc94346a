"""Keel's verifier: the mission model, the Z3 decision-graph prover, the TLC runner and
trace validation. The command-line entry point is ``keel-verify`` (``keel_verify.cli``)."""

# Keel's version is in VERSION at the repository root; tests/test_version.py checks
# this copy, which the installed package carries, agrees.
__version__ = "0.2.0"
