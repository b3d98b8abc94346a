-------------------- MODULE ValueFaultFutureLineageKept ---------------------
(***************************************************************************)
(* Mutant of ValueFault: a task that starts from a state of a lineage of   *)
(* an epoch above its host's view runs on in that lineage (RunLineage      *)
(* removed, ConfigSwitch::activate before keel-sim's liar seed 12602).     *)
(* With the lying Storage node ST1 (MCValueFaultLineageStorage), a host    *)
(* restores its state of a lineage of epoch 3: TLC must report             *)
(* NoFutureLineageInv violated (exit 12). With a correct Storage node      *)
(* (MCValueFaultLineage), ST1 follows the liar PN2's epoch 2 and stores    *)
(* its state of a lineage of that epoch; PN3, still in epoch 1, restores   *)
(* t2 from it at the first phase change and deactivates it at the second:  *)
(* its final flush, from the future, is refused for as long as PN3 stays   *)
(* in epoch 1, and TLC must report FlushLiveness violated (exit 13).       *)
(***************************************************************************)
EXTENDS MCValueFault

KeepLineage(n, l) == l

MutantSpec ==
    /\ Init
    /\ [][NextLineageBy(EpochInBounds, VersionInBounds, MayCommand, Checked, MayActivate,
                        MayAck, MayReply, MayWrite, PeersPrepared, Backed, WriteInEpoch,
                        ReplyInEpoch, KeepLineage, Adoptable)]_vars
    /\ LineageFairness
=============================================================================
