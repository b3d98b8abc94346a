"""keel-cluster: run one keel-node per node of a mission, on loopback or in network
namespaces, inject faults on a schedule, and measure what the OBC-NG paper measured."""
