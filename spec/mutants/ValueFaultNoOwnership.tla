----------------------- MODULE ValueFaultNoOwnership ------------------------
(***************************************************************************)
(* Mutant of ValueFault: a Command is followed from the master its view    *)
(* names whatever the epoch (rule 2 without epoch ownership). The liar PN1 *)
(* claims an epoch another node owns, a correct node follows it, and the   *)
(* epoch's owner takes over in it: TLC must report OneMasterPerEpochInv    *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCValueFault

AnyEpoch(n, s, v) ==
    /\ s = v.master
    /\ view[n].epoch <= v.epoch
    /\ v.epoch <= view[n].epoch + N

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, AnyEpoch, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
