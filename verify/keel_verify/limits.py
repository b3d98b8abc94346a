"""The runtime's capacity: how many nodes and how many tasks one mission may have.

These numbers are stated once, here, for the verifier; the C++ runtime (`core/`) and the
wire format must agree with them, because what the verifier proves every node must be
able to boot. A mission image records them in its ``capacity`` field, and
``keel-verify compile`` refuses a mission that exceeds them (rule ``out-of-range``, exit 2)
before it proves anything.
"""

from __future__ import annotations

# Nodes of one mission: a node's logical address is its index in the mission's node list,
# so the runtime's sets of nodes (failed, alive, in view) are bitsets of this many bits:
# core/fsm/types.hpp's kMaxNodes, where the capacity is stated once for the C++ runtime and
# from which its wire format derives (two-byte node ids, node sets of four 64-bit words;
# core/fsm/codec.hpp). tests/verify/test_compile.py checks that the two agree. What the
# verifier proves, every node must boot: a mission over the runtime's capacity is refused
# here, not at boot.
MAX_NODES = 256

# Tasks of one mission, across every phase (core/fsm/types.hpp's kMaxTasks).
MAX_TASKS = 1024


def capacity() -> dict[str, int]:
    """The capacity as a mission image records it."""
    return {"max_nodes": MAX_NODES, "max_tasks": MAX_TASKS}
