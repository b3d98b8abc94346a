------------------------ MODULE RejoinAfterWithdrawal ------------------------
(***************************************************************************)
(* Mutant of Rejoin under recurring crashes: the Master readmits a node    *)
(* only once no monitor holds it failed any more (it waits for every       *)
(* declaration to be withdrawn, as for a node that was never excluded).    *)
(* A monitor withdraws a declaration only of a node not excluded, so the   *)
(* declarations of an excluded node stand, and a restarted node is never   *)
(* readmitted: TLC must report ReadmitLiveness violated (exit 13).         *)
(***************************************************************************)
EXTENDS MCRejoinLive

WaitingReadmit(n) ==
    /\ \A m \in Monitors \ {n} : n \notin failed[m]
    /\ ReadmitBy(n, TRUE)

MutantNext ==
    (\/ LNext /\ UNCHANGED rejoinVars
     \/ \E n \in Nodes : Restart(n)
     \/ \E n \in Nodes : WaitingReadmit(n))
    /\ (CrashStep => Whole)

MutantFairness ==
    /\ \A n \in Nodes : WF_everything(SendHeartbeat(n) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ \A m \in Monitors, n \in Nodes :
          WF_everything(ReceiveHeartbeat(m, n) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ \A m \in Monitors, n \in Nodes :
          WF_everything(~alive[m] /\ LoseHeartbeat(n, m) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ WF_everything(LTickBy(MissLimit, Quorum, 1, TRUE) /\ UNCHANGED rejoinVars)
    /\ \A n \in Nodes :
          WF_everything(LExcludeBy(n, MissLimit, Quorum, TRUE) /\ UNCHANGED rejoinVars)
    /\ \A n \in Nodes : SF_everything(WaitingReadmit(n))

MutantSpec == RInit /\ [][MutantNext]_everything /\ MutantFairness
=============================================================================
