---------------------------- MODULE MCRejoinLive ----------------------------
(***************************************************************************)
(* Liveness of Rejoin under recurring crashes: a restarted node is         *)
(* eventually readmitted (ReadmitLiveness), for as long as it stays up.    *)
(*                                                                         *)
(* The faults recur for ever, one at a time: a node (the Master too)      *)
(* crashes only while the cluster is whole (every node up and readmitted), *)
(* as MCRejoin's MaxFaulty 1 reads once a restart counts as a failure      *)
(* until its readmission (RNoFalseExclusionInv); a crashed node may        *)
(* restart, or stay down for good (restarts are not fair: the property is  *)
(* about a node that did restart). Everything else is MCRejoin's: PN1 the  *)
(* Master, PN2 and PN3 the Observers, no loss on healthy links, no         *)
(* omission. No action constraint: MCRejoin's one-sender reduction is      *)
(* argued for safety only.                                                 *)
(*                                                                         *)
(* Fairness, of the protocol only: heartbeats are sent and received (and a *)
(* heartbeat to a crashed monitor is lost), periods end, the Master (or    *)
(* its successor) excludes a node it has the evidence for, and the Master  *)
(* readmits a node it hears, strongly fair: it hears it in every period,   *)
(* but a period may end before it acts (ReadmitBy reads the period's       *)
(* `heard`), so weak fairness would allow it never to.                     *)
(***************************************************************************)
EXTENDS MCRejoin

\* The cluster is whole: every node up, none excluded, none awaiting readmission.
Whole == (\A n \in Nodes : alive[n]) /\ excluded = {} /\ rebooted = {}

\* A step in which a node crashes.
CrashStep == \E n \in Nodes : alive[n] /\ ~alive'[n]

\* Rejoin's next-state relation, with a crash only while the cluster is whole.
LiveNext == RNext /\ (CrashStep => Whole)

\* The protocol's fairness.
LiveFairness ==
    /\ \A n \in Nodes : WF_everything(SendHeartbeat(n) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ \A m \in Monitors, n \in Nodes :
          WF_everything(ReceiveHeartbeat(m, n) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ \A m \in Monitors, n \in Nodes :
          WF_everything(~alive[m] /\ LoseHeartbeat(n, m) /\ UNCHANGED <<leaseVars, rejoinVars>>)
    /\ WF_everything(LTickBy(MissLimit, Quorum, 1, TRUE) /\ UNCHANGED rejoinVars)
    /\ \A n \in Nodes :
          WF_everything(LExcludeBy(n, MissLimit, Quorum, TRUE) /\ UNCHANGED rejoinVars)
    /\ \A n \in Nodes : SF_everything(Readmit(n))

LiveSpec == RInit /\ [][LiveNext]_everything /\ LiveFairness

\* A restarted node that stays up is readmitted.
ReadmitLiveness ==
    \A n \in Nodes : (n \in rebooted /\ alive[n]) ~> (n \notin rebooted \/ ~alive[n])

\* Witness: faults recur; the first Master crashed, restarted and was readmitted, and then
\* another node crashed (the cluster was whole again in between).
WitnessReadmitThenCrashInv ==
    ~(S1 \in rejoined /\ \E n \in Nodes \ {S1} : ~alive[n])
=============================================================================
