------------------------ MODULE ElectionNoMasterLeft ------------------------
(***************************************************************************)
(* Mutant of ElectionLiar: no Observer declares a Master that left its     *)
(* view (rule (2) removed; keel-sim --mutant no-master-left). PN1, the     *)
(* lying Master, sends PN3 alone a Command of its epoch 4, hands PN2 epoch *)
(* 3 naming PN3 its Master, crashes and restarts: PN3 never takes an epoch *)
(* below its own, PN2 waits for PN3, which it hears every period, PN3 for  *)
(* PN2, ahead of it in the succession of epoch 4, and PN1 waits to be      *)
(* commanded: no Master ever again (earth-observation seed 13921). TLC     *)
(* must report AgreementLiveness violated in MCElectionLiarLeft (exit 13). *)
(* Here the liar hands an epoch over only in the name of a node that       *)
(* follows a newer one, as in seed 13921 (MutantLiarNext): a hand-over     *)
(* naming a node that never takes it leaves no Master without rule (2)     *)
(* too, in fewer steps, which is ElectionLeftAheadOnly's counterexample;   *)
(* so TLC reports the half of rule (2) that mutant keeps.                  *)
(***************************************************************************)
EXTENDS MCElectionLiar

\* The liar of seed 13921: a hand-over names a node that follows an epoch above it.
MutantLiarNext ==
    \/ \E x \in Nodes, e \in ForgeableEpochs : ForgeCommand(x, e)
    \/ \E x, r \in Nodes, e \in ForgeableEpochs, excl \in BOOLEAN :
          ForgeHandOver(x, r, e, excl) /\ epoch[r] > e

MutantNext ==
    \/ LElectionNext
    \/ \E x \in Nodes, c \in forged : ReceiveForged(x, c)
    \/ MutantLiarNext
    \/ LEnvironmentNext

MutantFairness ==
    /\ \A n, m \in Nodes : WF_allVars(~alive[m] /\ LSuspect(n, m))
    /\ \A n, m \in Nodes : WF_allVars(LSuspectFenced(n, m))
    /\ \A n \in Nodes : WF_allVars(LBecomeMaster(n))
    /\ \A n \in Nodes : WF_allVars(\E e \in {epoch[x] : x \in Nodes} : Reclaim(n, e))
    /\ WF_allVars(\E n \in Nodes : LWarmBoot(n))
    /\ \A n \in Nodes : WF_allVars(LBroadcastCommand(n))
    /\ \A n \in Nodes : WF_allVars(\E msg \in msgs : LReceiveCommand(n, msg))
    /\ \A r \in Nodes : WF_allVars(\E h \in handOvers : LTakeHandOver(r, h))

MutantSpec == LInit /\ [][MutantNext]_allVars /\ MutantFairness
=============================================================================
