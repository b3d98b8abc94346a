---------------------------- MODULE MCElectionLiar ----------------------------
(***************************************************************************)
(* Models of ElectionLiar for CI: the paper's prototype, PN1 the Master,   *)
(* PN2 the higher- and PN3 the lower-priority Observer (MCMasterElection's *)
(* nodes), PN1 the liar. One crash and one restart (the liar's, for        *)
(* AgreementLiveness), no false declaration.                               *)
(*  - MCElectionLiarHandOver.cfg, rule (1): two forged messages, a         *)
(*    hand-over naming any node. Safety only (ElectionLiar's header: a     *)
(*    hand-over naming a node that never takes it leaves no Master).       *)
(*    Mutant ElectionHandOverExcludesReceiver; witness                     *)
(*    WitnessHandOverRefused.                                              *)
(*  - MCElectionLiarLeft.cfg, rule (2): three forged messages, a hand-over *)
(*    naming only a node that follows a newer epoch (seed 13921's). Checks *)
(*    AgreementLiveness too. Mutant ElectionNoMasterLeft; witness          *)
(*    WitnessLeftTakeOver.                                                 *)
(*                                                                         *)
(* No symmetry: the priority order tells the nodes apart, and              *)
(* AgreementLiveness is a liveness property.                               *)
(***************************************************************************)
EXTENDS ElectionLiar

CONSTANTS PN1, PN2, PN3
MCPriority == <<PN1, PN2, PN3>>

\* Witness (MCElectionLiarHandOver): a hand-over of the liar's that excludes its receiver
\* is in flight, and passes every other check the receiver makes: only rule (1) refuses it.
WitnessHandOverRefusedInv ==
    ~\E c \in forged :
        /\ IsHandOver(c) /\ c.excl
        /\ lying /\ alive[c.to] /\ InBound(c.to, c) /\ Authorized(c.to, c)

\* Witness (MCElectionLiarLeft): a node declared the Master of its view left and took over
\* above the epoch that Master follows, and every node follows a Master (Agreed).
WitnessLeftTakeOverInv == ~(leftTakeOver /\ Agreed)
=============================================================================
