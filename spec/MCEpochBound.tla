---------------------------- MODULE MCEpochBound ----------------------------
(***************************************************************************)
(* The CI model of EpochBound (MCEpochBound.cfg): the prototype's three    *)
(* processing nodes PN1, PN2, PN3 in succession (a lap of 3), PN3 the      *)
(* liar, MaxEpoch 12 (MaxAdoptable 9), MissLimit 2, two periods, one       *)
(* restart besides PN2's boot at the start, one take-over or readmission. *)
(* PN1, the first                                                          *)
(* Master, knows its epoch from the start; PN2 knows none until its first  *)
(* Command. Checks TopLapInv and LapPerPeriodInv: 22,121 states (with      *)
(* MaxTakeOvers 2, by hand: 67,087, neither property fails).              *)
(*                                                                         *)
(* By hand, without ReadmitBy (the same model with other constants; one    *)
(* worker), neither                                                        *)
(* property fails: with three periods (32,593 states, 50 s); PN2 the liar  *)
(* with MaxEpoch 15 (34,893); MaxEpoch 19 (52,452); and PN1, the first     *)
(* Master, the liar (both correct nodes then boot knowing no epoch), with  *)
(* MaxEpoch 19 and one restart (45,488). The mutant                        *)
(* EpochBoundOpenedUnknown runs with MaxEpoch 19, no restart and no        *)
(* take-over (the manifest's constants): its counterexample needs an epoch *)
(* beyond the allowance of two periods. The base model with those          *)
(* constants passes (601 states).                                          *)
(*                                                                         *)
(* The runtime's former corroborated_epoch (a lap per period since boot,  *)
(* above the highest epoch heard since, not since that heartbeat) is no    *)
(* mutant here:                                                            *)
(* it needs the raw epochs heard, which the spec does not keep. By hand,   *)
(* with a copy of EpochBound whose cc holds the highest epoch heard and    *)
(* whose bound adds a lap per period since boot, LapPerPeriodInv fails     *)
(* with MaxEpoch 19 and no take-over in 5 states: PN1 adopts the liar's 6  *)
(* in period 1, PN2 (booted at 0, no Command yet) hears it and follows the *)
(* liar's 12, 6 plus two laps, where the allowance is 10.                  *)
(*                                                                         *)
(* MCView is the model's VIEW: TLC tells states apart by what a step or a  *)
(* property can still read. Hidden: a node's cc and listened once it knows *)
(* its epoch (only a node that knows none reads them, and it knows none    *)
(* again only after a restart, which resets both), restarted once it was   *)
(* commanded (only the take-over's guard and a witness read it, of a node  *)
(* not commanded), opened once it was commanded (Knows is then true under  *)
(* either notion), and newerAge while no newer epoch is noted.             *)
(***************************************************************************)
EXTENDS EpochBound

CONSTANTS PN1, PN2, PN3

MCPriority == <<PN1, PN2, PN3>>

MCView ==
    <<now, epoch, master, commanded,
      [n \in Correct |-> commanded[n] \/ opened[n]],
      [n \in Correct |-> ~commanded[n] /\ restarted[n]],
      [n \in Correct |-> IF Knows(n) THEN MissLimit ELSE listened[n]],
      ceiling,
      [n \in Correct |-> IF Knows(n) THEN [m \in Correct |-> 0] ELSE cc[n]],
      newer,
      [n \in Correct |-> IF newer[n] = 0 THEN 0 ELSE newerAge[n]],
      boots, takeOvers, hMax, witnessed>>

(***************************************************************************)
(* Witnesses: each is an invariant TLC must find violated (manifest        *)
(* "witnesses"): the states the properties are about are reachable.        *)
(***************************************************************************)
\* The bound does not just refuse the liar: a correct node goes by an epoch of the liar's
\* more than a lap above the image's (PN1, the first Master, follows PN3's 6 in period 1,
\* its ceiling 7).
WitnessFarLiarInv == ~\E n \in Correct : Owner(epoch[n]) = Liar /\ epoch[n] > 1 + Lap
\* A restarted node follows a first Command above its own saved epoch's term: another
\* node's heartbeat corroborated it (PN1 follows PN3's 3; PN2 restarts at 1, hears PN1's 3
\* and follows PN3's 6, within 3 plus a lap).
WitnessBootCorroboratedInv == "bootCorroborated" \notin witnessed
\* A Master moves past an epoch of its own it never opened (the liar's heartbeat reports
\* it): AMasterMovesPastAnEpochOfItsOwnItNeverOpened (PN1 notes its 4 in period 0 and
\* opens 7 in period 2).
WitnessOwnPassedInv == "ownPassed" \notin witnessed
\* The width binds: a correct node that may take over has no epoch of its own left at or
\* below MaxAdoptable (its next one is in the top lap), so it does not.
WitnessNoEpochLeftInv ==
    ~\E n \in Correct \cap Processing :
        /\ ~master[n]
        /\ commanded[n] \/ (~restarted[n] /\ listened[n] >= MissLimit)
        /\ NextOwnedAbove(n, epoch[n]) > MaxAdoptable
\* A correct Master readmits a node, into an epoch of its own or handed over (ReadmitBy).
WitnessReadmittedInv == "readmitted" \notin witnessed
\* The width binds a readmission: a correct Master could not readmit into some processing
\* node's configuration, the next epoch that node owns being in the top lap (the runtime's
\* readmissions_refused).
WitnessReadmitBlockedInv ==
    ~\E m \in Correct : /\ master[m] /\ takeOvers < MaxTakeOvers
                        /\ \E r \in Processing : NextOwnedAbove(r, epoch[m]) > MaxAdoptable
\* A Master hands the view to a correct node, which adopts it and is its Master.
WitnessHandedOverInv ==
    ~\E m, r \in Correct : m # r /\ master[r] /\ ~master[m] /\ epoch[m] = epoch[r]
                         /\ Owner(epoch[r]) = r /\ "readmitted" \in witnessed
=============================================================================
