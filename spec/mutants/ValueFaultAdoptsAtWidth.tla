---------------------- MODULE ValueFaultAdoptsAtWidth -----------------------
(***************************************************************************)
(* Mutant of ValueFault: a correct node adopts a state of any count the    *)
(* wire carries (the adoption rule removed: Adoptable is TRUE, the runtime *)
(* as the protocol fuzzer found it). In MCValueFaultWidth the liar PN3,    *)
(* which the mission may place t1 on, writes t1 at the width (MaxVersion   *)
(* 2), and the correct Storage node keeps it; PN2 restores that state at   *)
(* the first phase change, from the liar's reply or the Storage node's,    *)
(* and steps to 3, a count the codec does not carry: TLC must report       *)
(* VersionBoundInv violated (exit 12). PN2's final flush of that count at  *)
(* the second phase change is dropped as out of bounds, so it is never     *)
(* acknowledged and PN2's switch waits for good: with the mutant           *)
(* ValueFaultAdoptsAtWidthStall (the same module) TLC must report          *)
(* FlushLiveness violated (exit 13).                                       *)
(***************************************************************************)
EXTENDS MCValueFault

AdoptsAny(v) == TRUE

MutantSpec ==
    /\ Init
    /\ [][NextLineageBy(EpochInBounds, VersionInBounds, MayCommand, Checked, MayActivate,
                        MayAck, MayReply, MayWrite, PeersPrepared, Backed, WriteInEpoch,
                        ReplyInEpoch, RunLineage, AdoptsAny)]_vars
    /\ LineageFairness
=============================================================================
