---------------------- MODULE ValueFaultNoSenderCheck -----------------------
(***************************************************************************)
(* Mutant of ValueFault: a Command of an epoch its sender owns is followed *)
(* whatever master its view names (rule 2 without "the sender is the       *)
(* view's master"). The liar PN1 sends PN2 a view of its own epoch, 1,     *)
(* that names PN2 its master (the graph's edge for PN1's failure), while   *)
(* PN3 follows PN1 in that epoch: TLC must report OneMasterPerEpochInv     *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCValueFault

AnyMaster(n, s, v) ==
    /\ Owner(v.epoch) = s
    /\ view[n].epoch <= v.epoch
    /\ v.epoch <= view[n].epoch + N

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, AnyMaster, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
