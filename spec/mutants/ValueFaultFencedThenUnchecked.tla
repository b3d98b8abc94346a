------------------- MODULE ValueFaultFencedThenUnchecked --------------------
(***************************************************************************)
(* Mutant of ValueFault: rule 5 measures the exclusions a view adds        *)
(* against the failed set of the node's current view, not against vetted,  *)
(* the failed set of the last view it followed with the check. The liar    *)
(* PN1, the Master, fences PN2 and PN3 with the next switch (1, 1) to      *)
(* Safe, which PN2 follows unchecked since it excludes PN2; then it skips  *)
(* a switch number and readmits PN2 with (1, 3), P1 without PN3, which     *)
(* places t1 on PN2. Measured against (1, 1)'s failed set that view adds   *)
(* no exclusion, so PN2 follows it, waits for no "Prepared" of the         *)
(* excluded PN3 and starts t1, which PN3, never commanded, still runs: TLC *)
(* must report NoDoubleActivationInv violated (exit 12) with MaxSeq = 3.   *)
(***************************************************************************)
EXTENDS MCValueFault

BackedSinceView(n, s, v) == BackedSince(view[n].failed, n, s, v)

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, BackedSinceView)]_vars
=============================================================================
