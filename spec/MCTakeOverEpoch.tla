---------------------------- MODULE MCTakeOverEpoch ----------------------------
(***************************************************************************)
(* Model of TakeOverEpoch for CI (MCTakeOverEpoch.cfg): the paper's        *)
(* prototype, PN1 the Master, PN2 the higher- and PN3 the lower-priority   *)
(* Observer (MCMasterElection's nodes), PN1 the liar: one forged Command   *)
(* of an epoch of its own to one node, PN1's crash, no restart, no false   *)
(* declaration. Mutant TakeOverOwnEpochOnly; witness                       *)
(* WitnessTakeOverAboveVoter.                                              *)
(*                                                                         *)
(* No symmetry: the priority order tells the nodes apart, and              *)
(* TakeOverLiveness is a liveness property.                                *)
(***************************************************************************)
EXTENDS TakeOverEpoch

CONSTANTS PN1, PN2, PN3
MCPriority == <<PN1, PN2, PN3>>

\* Witness: a take-over opened above the epoch of a voter (of the node it replaced), the
\* liar crashed, and its Master holds its lease with every running node following it.
WitnessTakeOverAboveVoterInv == ~(aboveVoter /\ ~lying /\ LeaseHeld)
=============================================================================
