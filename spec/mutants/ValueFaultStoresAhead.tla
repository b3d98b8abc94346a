----------------------- MODULE ValueFaultStoresAhead ------------------------
(***************************************************************************)
(* Mutant of ValueFault: the Storage node stores a checkpoint write of a   *)
(* lineage of an epoch it has not adopted (WriteInEpoch without "nor than  *)
(* the Storage node's own epoch", the rule before keel-sim's liar seeds    *)
(* 244 and 1544). The liar PN2, which may host t2, writes a state of a     *)
(* lineage of its epoch 2 before the Storage node has followed any Command *)
(* of that epoch: TLC must report StoredAdoptedInv violated (exit 12) in   *)
(* MCValueFaultLineage.                                                    *)
(***************************************************************************)
EXTENDS MCValueFault

WriterEpochOnly(l, e) == LineageEpoch(l) <= e

MutantSpec ==
    Init /\ [][NextLineageBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                             MayActivate, MayAck, MayReply, MayWrite, PeersPrepared,
                             Backed, WriterEpochOnly, ReplyInEpoch, RunLineage,
                             Adoptable)]_vars
=============================================================================
