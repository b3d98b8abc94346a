----------------------- MODULE ValueFaultFutureReply ------------------------
(***************************************************************************)
(* Mutant of ValueFault: a restore takes a reply from a node other than    *)
(* the Storage node whatever the lineage of the state it holds             *)
(* (ReplyInEpoch removed). PN3 starts t2 from the liar's reply of a        *)
(* lineage of epoch 2, which no correct node has adopted: TLC must report  *)
(* NoFutureStateInv violated (exit 12) in MCValueFaultLineage.             *)
(***************************************************************************)
EXTENDS MCValueFault

AnyLineageReply(n, s, l) == TRUE

MutantSpec ==
    Init /\ [][NextLineageBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                             MayActivate, MayAck, MayReply, MayWrite, PeersPrepared,
                             Backed, WriteInEpoch, AnyLineageReply, RunLineage,
                             Adoptable)]_vars
=============================================================================
