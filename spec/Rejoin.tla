------------------------------- MODULE Rejoin -------------------------------
(***************************************************************************)
(* Reintegration (fault model 2, rule 4): a restarted, healed or falsely  *)
(* excluded node comes back.                                               *)
(*                                                                         *)
(* Lease.tla makes exclusion safe while the excluded node may be alive:    *)
(* it stops before the cluster decides against it, and is never           *)
(* acknowledged again. Without more, exclusion is permanent: one restart  *)
(* spends the cluster's tolerance for good. This spec adds the way back.  *)
(*                                                                         *)
(* Restart. A crashed node that the cluster excluded boots again with a    *)
(* fresh monitor (it declares no one) and no acknowledgement (its lease    *)
(* has lapsed: it runs nothing). A node that restarts before its exclusion *)
(* is excluded on its own word first (the runtime's incarnation), which    *)
(* this spec folds into the crash.                                         *)
(*                                                                         *)
(* Rule 4, readmission. The Master, holding its own lease, readmits an     *)
(* excluded node it hears: the node leaves `excluded`, every monitor       *)
(* forgets what it counted and declared about it, and it forgets what it  *)
(* declared itself (what a cut-off node declared while isolated is no      *)
(* evidence: a healed node that kept it would be the second voice of the  *)
(* next faulty monitor). A readmitted node runs only once its voters       *)
(* acknowledge it again (the lease, unchanged). As a voter it counts from *)
(* zero: the Master, which sends the view, takes it as a fresh             *)
(* acknowledgement; every other node waits for its acknowledgements (an   *)
(* excluded node among them must not run on a readmitted voter's silence: *)
(* TLC found that when every node took it as fresh). When the readmitted   *)
(* node                                                                    *)
(* is first in the succession it becomes the Master again: in the runtime *)
(* the Master hands over with a Command for the readmitted node's epoch,   *)
(* which it adopts itself (it stops driving at once), and the new Master  *)
(* drives only once it holds its lease, as here.                           *)
(*                                                                         *)
(* Which configuration the cluster returns to is the decision graph's      *)
(* business (docs/missions.md: recovery returns to the configuration of    *)
(* the smaller failed set, a state keel-verify check has already proved);  *)
(* how tasks move without running twice is ConfigSwitch's (a readmission   *)
(* is a planned switch).                                                   *)
(*                                                                         *)
(* Properties: Lease's NoExcludedRunsInv and AckBoundInv, and              *)
(* RNoFalseExclusionInv: every excluded node crashed, is omissive, or has  *)
(* restarted since and awaits readmission. The mutant                     *)
(* mutants/RejoinKeepsDeclarations.tla readmits a node but leaves the     *)
(* monitors' declarations of it: a healthy node is excluded again on them. *)
(* Witnesses (MCRejoin.tla): a restart, a readmission, a readmitted node   *)
(* that runs again, and a readmitted first Master that is Master again.    *)
(***************************************************************************)
EXTENDS Lease

VARIABLES
    rebooted,  \* SUBSET Nodes: restarted since their exclusion, not yet readmitted
    rejoined   \* SUBSET Nodes: readmitted at least once (history, for the witnesses)

rejoinVars == <<rebooted, rejoined>>
everything == <<vars, leaseVars, rejoinVars>>

RTypeOK == LTypeOK /\ rebooted \subseteq Nodes /\ rejoined \subseteq Nodes

RInit == LInit /\ rebooted = {} /\ rejoined = {}

\* A crashed, excluded node boots again. It joins the period under way as one that has
\* sent (its first heartbeat goes out with the next period).
Restart(n) ==
    /\ ~alive[n]
    /\ n \in excluded
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ sent' = [sent EXCEPT ![n] = TRUE]
    /\ failed' = IF n \in Monitors THEN [failed EXCEPT ![n] = {}] ELSE failed
    /\ missed' = IF n \in Monitors THEN [missed EXCEPT ![n] = [x \in Nodes |-> 0]] ELSE missed
    \* A fresh monitor does not count the period it booted in (it did not see all of it):
    \* as if it had heard everyone. (TLC found the lease of a healthy Master lapse on a
    \* readmitted Observer's count of the period it restarted in.)
    /\ heard' = IF n \in Monitors THEN [heard EXCEPT ![n] = Nodes] ELSE heard
    /\ ackAge' = [ackAge EXCEPT ![n] = [v \in Monitors |-> MaxAge]]
    /\ running' = [running EXCEPT ![n] = FALSE]
    /\ downFor' = [downFor EXCEPT ![n] = 0]
    /\ rebooted' = rebooted \cup {n}
    /\ UNCHANGED <<omissive, deaf, late, inFlight, lossRun, excluded, ackLoss,
                   resigned, rejoined>>

\* Rule 4: the Master readmits n. Parameterised so that a mutant can keep the other
\* monitors' declarations of n.
ReadmitBy(n, forgetDeclarations) ==
    /\ n \in excluded
    /\ alive[n]
    /\ DecidesBy(Master, n, MissLimit, Quorum, FALSE)
    /\ n \in heard[Master]
    /\ excluded' = excluded \ {n}
    /\ failed' = [m \in Monitors |->
                    IF m = n THEN {}
                    ELSE IF forgetDeclarations THEN failed[m] \ {n} ELSE failed[m]]
    /\ missed' = [m \in Monitors |-> [x \in Nodes |->
                    IF m = n \/ (x = n /\ forgetDeclarations) THEN 0 ELSE missed[m][x]]]
    /\ rebooted' = rebooted \ {n}
    /\ rejoined' = rejoined \cup {n}
    /\ resigned' = resigned \ {n}
    \* n counts everyone from zero: as a voter on the Master, which sends the view, it is a
    \* fresh acknowledgement (the other nodes wait for n's own).
    /\ ackAge' = IF n \in Monitors THEN [ackAge EXCEPT ![Master][n] = 0] ELSE ackAge
    /\ UNCHANGED <<alive, omissive, deaf, late, sent, inFlight, lossRun, heard, downFor,
                   ackLoss>>
    \* Every node learns it (Lease's abstraction): voters change, leases with them.
    /\ running' = [x \in Nodes |-> (RunningBy(x, MissLimit, Quorum))']

Readmit(n) == ReadmitBy(n, TRUE)

\* Lease's next-state relation, with restarts and readmissions.
RNextBy(forgetDeclarations) ==
    \/ LNext /\ UNCHANGED rejoinVars
    \/ \E n \in Nodes : Restart(n)
    \/ \E n \in Nodes : ReadmitBy(n, forgetDeclarations)

RNext == RNextBy(TRUE)

RSpec == RInit /\ [][RNext]_everything

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* Exclusion's NoFalseExclusionInv, where a restart is a failure until readmission.
RNoFalseExclusionInv == \A n \in excluded : ~alive[n] \/ n \in omissive \/ n \in rebooted
=============================================================================
