----------------------- MODULE EpochBoundReadmitOpens -----------------------
(***************************************************************************)
(* Mutant of EpochBound: a readmission opens the next epoch of the Master  *)
(* it readmits into whatever it is, as NodeProtocol::consider_readmission  *)
(* did before readmissions_refused (the take-over and the reclaim checked  *)
(* the width; the readmission and the hand-over did not). In the C++, PN2, *)
(* Master of 16,777,211 after a warm boot near the width, handed the view  *)
(* to a restarted PN1 in 16,777,213, beyond the last adoptable 16,777,212, *)
(* adopted it first (its own Command), and every other node refused its    *)
(* Commands as proof (NoMasterReadmitsIntoAnEpochBeyondTheWidth). TLC must *)
(* report TopLapInv violated (exit 12).                                    *)
(***************************************************************************)
EXTENDS MCEpochBound

AnyOpen(o) == TRUE

MutantNext ==
    \/ NextBy(Knows, FirstBound, Ceiling, CeilingAfter, OpenOk)
    \/ \E n \in Correct : ReadmitBy(AnyOpen, n)

MutantSpec == Init /\ [][MutantNext]_vars
=============================================================================
