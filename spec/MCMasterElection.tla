--------------------------- MODULE MCMasterElection ---------------------------
(***************************************************************************)
(* Model of MasterElection for CI: the paper's prototype, PN1 the Master,  *)
(* PN2 the higher-priority and PN3 the lower-priority Observer. Two        *)
(* crashes let both the Master and the higher-priority Observer fail; one  *)
(* restart lets a crashed node rejoin; one false declaration lets an       *)
(* Observer wrongly depose a running Master. No symmetry: the priority     *)
(* order tells the nodes apart, and MasterLiveness is a liveness property. *)
(* MCMasterElectionHandOver lets the Master hand its mastership over once  *)
(* (MaxHandOvers = 1), with one crash and one restart.                     *)
(* MCMasterElectionFenced lets a Master fence two live nodes (MaxFences =  *)
(* 2), with one false declaration, one crash and one restart.              *)
(***************************************************************************)
EXTENDS MasterElection

CONSTANTS PN1, PN2, PN3
MCPriority == <<PN1, PN2, PN3>>

\* Witness (MCMasterElectionPowerCycle): every node crashed and restarted, and all are
\* running again: the whole-cluster power cycle MasterLiveness is checked through.
WitnessPowerCycleInv == ~(\A x \in Nodes : alive[x] /\ restartEpoch[x] > 0)

\* Witness (MCMasterElectionHandOver): a node became Master by a hand-over. It is Master
\* of the epoch handed to it and has not commanded in it yet, which only TakeHandOver
\* leads to (BecomeMaster, WarmBoot and Init send the new Master's command at once).
WitnessHandOverInv ==
    ~\E h \in handOvers :
        /\ alive[h.to] /\ role[h.to] = "Master" /\ epoch[h.to] = h.epoch
        /\ [epoch |-> h.epoch, from |-> h.to] \notin msgs

\* Witness (MCMasterElectionHandOver): a hand-over is in flight to a running node that
\* restarted since it was sent, and is fresh for it: only the boot it names keeps that
\* node from taking it (NoStaleMastershipInv needs the boot check here).
WitnessStaleHandOverInv ==
    ~\E h \in handOvers :
        alive[h.to] /\ h.boot # boot[h.to] /\ Fresh(h.to, h)

\* Witness (MCMasterElectionFenced): a warm boot may happen with a fenced node, which counts
\* as idle only because it is fenced (it obeys a Master: it does not wait). Every node is
\* idle, and WarmBoot, which has no other guard, is enabled.
WitnessFencedWarmBootInv ==
    ~/\ \A x \in Nodes : Idle(x)
     /\ \E x \in Nodes : alive[x] /\ fenced[x] /\ ~Waiting(x)
=============================================================================
