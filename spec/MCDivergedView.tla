---------------------------- MODULE MCDivergedView ----------------------------
(***************************************************************************)
(* Models of DivergedView. PN1 is the Master of epoch 1 and the liar; it   *)
(* makes one switch, (1, 1), with a copy per correct node (or, in          *)
(* MCDivergedViewLost and MCDivergedViewTwoIds, per correct node it        *)
(* reaches; in MCDivergedViewTwoIds it may switch again, to (1, 2), with a *)
(* copy per correct node it left out), crashes and may restart (honest);   *)
(* no false declaration; ElectionLiar's other lies off (MaxLies = 0).      *)
(*  - MCDivergedView.cfg (CI): the paper's prototype, PN2 the higher- and  *)
(*    PN3 the lower-priority Observer (MCElectionLiar's nodes); copies Std *)
(*    (PN2 and PN3 Observers: seed 30979's S1), S1b (the same Observers,   *)
(*    another digest: a task placed elsewhere) and Safe (safe mode from    *)
(*    P3: PN3 the one Observer, PN2 a Worker). Mutants DivergedNone (seed  *)
(*    30979) and DivergedSameView; witnesses WitnessDivergedPassOver,      *)
(*    WitnessTwoCopies and WitnessTwoTakeOversOneId.                       *)
(*  - MCDivergedViewLost.cfg (CI): MCDivergedView's nodes and copies, the  *)
(*    liar's switch reaching a non-empty set of correct nodes              *)
(*    (MCLiarSwitchToLost: a copy never sent, or lost for good when the    *)
(*    liar crashes). Mutant DivergedSameIdOnly (PN3 in (1, 0) waits for    *)
(*    ever for PN2, a Worker of (1, 1) Safe); witness                      *)
(*    WitnessNewerSwitchPassOver.                                          *)
(*  - MCDivergedViewTwoIds.cfg (CI): MCDivergedViewLost, and the liar may  *)
(*    switch again, to (1, 2), with a copy to each of a non-empty set of   *)
(*    the correct nodes its first switch left out (MCLiarSwitchAgainTo):   *)
(*    copies of two ids. Mutant DivergedNoNeverPrepared (PN3 in (1, 2)     *)
(*    waits for ever for PN2, a Worker of (1, 1) Safe); witness            *)
(*    WitnessNeverPreparedPassOver.                                        *)
(*  - MCDivergedViewFour.cfg (bench): PN4 a Worker of Std, and Safe's      *)
(*    Observers PN3 and PN4, so that a node passed over may be passed over *)
(*    by a Worker of another copy, and the taker may itself be an Observer *)
(*    only in its own copy.                                                *)
(*                                                                         *)
(* No symmetry: the priority order tells the nodes apart, and              *)
(* DivergedLiveness is a liveness property.                                *)
(***************************************************************************)
EXTENDS DivergedView

CONSTANTS PN1, PN2, PN3, PN4, S1b, Safe
MCPriority == <<PN1, PN2, PN3>>
MCCopyObservers == [c \in {Std, S1b, Safe} |-> IF c = Safe THEN {PN3} ELSE {PN2, PN3}]
MCPriorityFour == <<PN1, PN2, PN3, PN4>>
MCCopyObserversFour ==
    [c \in {Std, S1b, Safe} |-> IF c = Safe THEN {PN3, PN4} ELSE {PN2, PN3}]

\* The liar's switch may miss correct nodes (a copy never sent, or lost for good when the
\* liar crashes): a copy to each of a non-empty set of correct nodes.
MCLiarSwitchToLost == UNION {[to -> Copies] : to \in (SUBSET Correct) \ {{}}}

\* The liar may switch again, to (1, 2), sending a copy to each of a non-empty set of the
\* correct nodes its first switch left out (ForgeSwitchAgain): copies of two ids.
MCLiarSwitchAgainTo == MCLiarSwitchToLost

\* Witness: a take-over passed over a member that prepared another view under the id of the
\* taker's, and every running node follows one Master.
WitnessDivergedPassOverInv == ~(passedDiverged /\ Agreed)

\* Witness: a take-over passed over a member whose Prepared names a newer switch of the
\* taker's view's epoch, and every running node follows one Master.
WitnessNewerSwitchPassOverInv == ~(passedNewer /\ Agreed)

\* Witness: a take-over passed over a member that never prepared the taker's view, neither
\* another copy under its id nor a newer switch of its epoch (NeverPrepared alone), and
\* that prepared an older switch of its epoch (copies of two ids), and every running node
\* follows one Master.
WitnessNeverPreparedPassOverInv == ~(passedNever /\ Agreed)

\* Witness: two copies under one id reached two correct running nodes.
WitnessTwoCopiesInv ==
    ~\E x, y \in Correct :
        /\ x # y /\ alive[x] /\ alive[y]
        /\ epoch[x] = epoch[y] /\ seq[x] = seq[y] /\ seq[x] >= 1
        /\ copy[x] # copy[y]

\* Witness: two take-overs at once from two copies of one id, both running as Masters
\* (what OneTakeOverPerViewInv allows: each opened an epoch of its own).
WitnessTwoTakeOversOneIdInv ==
    ~\E n, m \in Nodes :
        /\ n # m /\ alive[n] /\ alive[m]
        /\ role[n] = "Master" /\ role[m] = "Master"
        /\ takenFrom[n].epoch # 0
        /\ takenFrom[n].epoch = takenFrom[m].epoch /\ takenFrom[n].seq = takenFrom[m].seq
        /\ takenFrom[n].copy # takenFrom[m].copy
=============================================================================
