------------------------ MODULE ElectionLeftAheadOnly ------------------------
(***************************************************************************)
(* Mutant of ElectionLiar: rule (2) as it was, a Master has left its       *)
(* Observer's view only when its heartbeats say an epoch above the view's, *)
(* not below it. PN1, the lying Master, hands PN2 epoch 3 naming PN3,      *)
(* which stays in epoch 1, crashes and restarts: PN2 waits for PN3, whose  *)
(* heartbeats say an epoch below its view's, PN3 for PN2, the first        *)
(* Observer of epoch 1, which it hears every period, and PN1 waits to be   *)
(* commanded: no Master ever again. TLC must report AgreementLiveness      *)
(* violated in MCElectionLiarLeft (exit 13).                               *)
(***************************************************************************)
EXTENDS MCElectionLiar

\* The old rule: the Master of n's view follows a newer epoch than n's.
LeftAhead(n, m) == Left(n, m) /\ epoch[m] > epoch[n]

MutantNext ==
    \/ LElectionNext
    \/ \E n, m \in Nodes : SuspectLeftBy(LeftAhead, n, m)
    \/ \E x \in Nodes, c \in forged : ReceiveForged(x, c)
    \/ LiarNext
    \/ LEnvironmentNext

MutantFairness ==
    /\ \A n, m \in Nodes : WF_allVars(~alive[m] /\ LSuspect(n, m))
    /\ \A n, m \in Nodes : WF_allVars(LSuspectFenced(n, m))
    /\ \A n, m \in Nodes : WF_allVars(SuspectLeftBy(LeftAhead, n, m))
    /\ \A n \in Nodes : WF_allVars(LBecomeMaster(n))
    /\ \A n \in Nodes : WF_allVars(\E e \in {epoch[x] : x \in Nodes} : Reclaim(n, e))
    /\ WF_allVars(\E n \in Nodes : LWarmBoot(n))
    /\ \A n \in Nodes : WF_allVars(LBroadcastCommand(n))
    /\ \A n \in Nodes : WF_allVars(\E msg \in msgs : LReceiveCommand(n, msg))
    /\ \A r \in Nodes : WF_allVars(\E h \in handOvers : LTakeHandOver(r, h))

MutantSpec == LInit /\ [][MutantNext]_allVars /\ MutantFairness
=============================================================================
