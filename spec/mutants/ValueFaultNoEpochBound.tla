----------------------- MODULE ValueFaultNoEpochBound -----------------------
(***************************************************************************)
(* Mutant of ValueFault: epochs are not checked against the wire's width   *)
(* (rule 1 without the epoch bound). The liar PN1 sends a Command of its   *)
(* next epoch, MaxEpoch + 1, one lap above its receivers' epoch: TLC must  *)
(* report EpochBoundInv violated (exit 12).                                *)
(***************************************************************************)
EXTENDS MCValueFault

AnyEpochValue(e) == e >= 1

MutantSpec ==
    Init /\ [][NextBy(AnyEpochValue, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
