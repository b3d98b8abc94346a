---------------------------- MODULE MCElectionLiar ----------------------------
(***************************************************************************)
(* Models of ElectionLiar for CI: the paper's prototype, PN1 the Master,   *)
(* PN2 the higher- and PN3 the lower-priority Observer (MCMasterElection's *)
(* nodes), PN1 the liar. One crash and one restart (the liar's, for        *)
(* AgreementLiveness), no false declaration.                               *)
(*  - MCElectionLiarHandOver.cfg, rule (1): two forged messages, a         *)
(*    hand-over naming any node. Safety only. Mutant                       *)
(*    ElectionHandOverExcludesReceiver; witness WitnessHandOverRefused.    *)
(*  - MCElectionLiarLeft.cfg, rule (2): two forged messages, a hand-over   *)
(*    naming any node. Checks AgreementLiveness too. Mutants               *)
(*    ElectionNoMasterLeft and ElectionLeftAheadOnly; witnesses            *)
(*    WitnessLeftTakeOver and WitnessBehindMasterLeft.                     *)
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

\* Witness (MCElectionLiarLeft): a node declared the Master of its view, a correct node
\* that follows an epoch below the view's (the liar handed the view over in its name),
\* took over above its own epoch, and, the liar crashed, every node runs and follows one
\* Master (Agreed).
WitnessBehindMasterLeftInv ==
    ~(behindTakeOver /\ ~lying /\ (\A n \in Nodes : alive[n]) /\ Agreed)
=============================================================================
