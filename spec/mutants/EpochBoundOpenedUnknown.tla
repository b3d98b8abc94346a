---------------------- MODULE EpochBoundOpenedUnknown -----------------------
(***************************************************************************)
(* Mutant of EpochBound (b), keel-sim's unbounded-master-epoch: a node     *)
(* that opened its epoch itself (the boot switch, a take-over) counts as   *)
(* one that knows none, so only the width bounds the newer epoch it moves  *)
(* past on a heartbeat. PN1, the first Master, notes its own epoch 13,     *)
(* which the liar's heartbeat reports, and moves past it to 16 two periods *)
(* later (keel-sim liar seed 12: a Master of epoch 2 past 13,425,727),     *)
(* where the allowance is 13. With the manifest's constants (MaxEpoch 19): *)
(* TLC must report LapPerPeriodInv violated (exit 12).                     *)
(***************************************************************************)
EXTENDS MCEpochBound

KnowsCommanded(n) == commanded[n]

MutantSpec ==
    Init /\ [][NextBy(KnowsCommanded, FirstBound, Ceiling, CeilingAfter, OpenOk)]_vars
=============================================================================
