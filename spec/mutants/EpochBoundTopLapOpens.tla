----------------------- MODULE EpochBoundTopLapOpens ------------------------
(***************************************************************************)
(* Mutant of EpochBound: the runtime's take_over and newer_epoch_ reclaim  *)
(* at 81049c4 open the next epoch their node owns whatever it is (only the *)
(* warm boot checks max_adoptable_epoch). PN1 follows the liar PN3's 3,    *)
(* and in period 2 takes over above an epoch 9 a voter acknowledges, into  *)
(* 10, beyond MaxAdoptable 9; every correct node would refuse its Commands *)
(* as proof (in the C++, PN2 moved past 16,777,212 to 16,777,214 on a      *)
(* liar's heartbeat, and PN1 and ST1 refused its Commands as proof). TLC   *)
(* must report TopLapInv violated (exit 12).                               *)
(***************************************************************************)
EXTENDS MCEpochBound

AnyOpen(o) == TRUE

MutantSpec == Init /\ [][NextBy(Knows, FirstBound, Ceiling, CeilingAfter, AnyOpen)]_vars
=============================================================================
