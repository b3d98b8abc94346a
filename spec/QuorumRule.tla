----------------------------- MODULE QuorumRule -----------------------------
(***************************************************************************)
(* Rule 1 of spec/Quorum.tla, the exclusion quorum, as arithmetic without  *)
(* constants: Quorum.tla model-checks it and TraceConfigSwitch checks each *)
(* of the Master's exclusions in a trace against the same definition (the  *)
(* runtime's quorum_needed in core/fsm/node_protocol.cpp).                 *)
(***************************************************************************)
EXTENDS Naturals, FiniteSets

Max(a, b) == IF a > b THEN a ELSE b
Min(a, b) == IF a < b THEN a ELSE b

\* Of the members `mem`, a majority, at most the voters (x left out), at least one.
Needed(mem, x) == Max(1, Min(Cardinality(mem) \div 2 + 1, Cardinality(mem \ {x})))
=============================================================================
