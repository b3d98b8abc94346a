--------------------------- MODULE MCMasterElection ---------------------------
(***************************************************************************)
(* Model of MasterElection for CI: the paper's prototype, PN1 the Master,  *)
(* PN2 the higher-priority and PN3 the lower-priority Observer. Two        *)
(* crashes let both the Master and the higher-priority Observer fail; one  *)
(* restart lets a crashed node rejoin; one false declaration lets an       *)
(* Observer wrongly depose a running Master. No symmetry: the priority     *)
(* order tells the nodes apart, and MasterLiveness is a liveness property. *)
(***************************************************************************)
EXTENDS MasterElection

CONSTANTS PN1, PN2, PN3
MCPriority == <<PN1, PN2, PN3>>

\* Witness (MCMasterElectionPowerCycle): every node crashed and restarted, and all are
\* running again: the whole-cluster power cycle MasterLiveness is checked through.
WitnessPowerCycleInv == ~(\A x \in Nodes : alive[x] /\ restartEpoch[x] > 0)
=============================================================================
