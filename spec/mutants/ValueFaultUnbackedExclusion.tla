-------------------- MODULE ValueFaultUnbackedExclusion ---------------------
(***************************************************************************)
(* Mutant of ValueFault: a node follows a Command that excludes a node no  *)
(* other node declared failed (no rule 5). The liar PN1, the Master, sends *)
(* PN2 the graph's edge for PN3's failure, a valid next switch that places *)
(* t1 on PN2; PN2 waits for no "Prepared" of the excluded PN3 and starts   *)
(* t1, which PN3, alive and never commanded, still runs: TLC must report   *)
(* NoDoubleActivationInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCValueFault

Unbacked(n, s, v) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Unbacked)]_vars
=============================================================================
