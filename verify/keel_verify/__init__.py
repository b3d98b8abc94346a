"""Keel's verifier: the mission model, the Z3 decision-graph prover, the TLC runner and
trace validation. The command-line entry point is ``keel-verify`` (``keel_verify.cli``)."""

__version__ = "0.1.0"
