"""Decision-graph synthesis and repair suggestions (Z3)."""
