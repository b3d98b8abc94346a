"""keel-cluster: run one keel-node per node of a mission, on loopback or in network
namespaces, inject faults on a schedule, and measure what the OBC-NG paper measured."""

# Keel's version is in VERSION at the repository root; tests/test_version.py checks
# this copy, which the installed package carries, agrees.
__version__ = "0.2.0"
