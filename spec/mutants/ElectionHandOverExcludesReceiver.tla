------------------- MODULE ElectionHandOverExcludesReceiver ------------------
(***************************************************************************)
(* Mutant of ElectionLiar: a hand-over is taken whatever its view excludes *)
(* (rule (1) removed; in the runtime, NodeProtocol::handle_command without *)
(* the check that Mutant::no_receiver_checks lifts with every other). The  *)
(* liar, Master of PN2's view, hands PN2 the epoch of another node in a    *)
(* view that excludes PN2, and PN2 follows it unchecked: fenced in that    *)
(* node's name, though that node excluded no one (prototype3 seed 119042). *)
(* TLC must report NoFenceInAnotherNameInv violated in                     *)
(* MCElectionLiarHandOver (exit 12).                                       *)
(***************************************************************************)
EXTENDS MCElectionLiar

AnyView(x, c) == TRUE

AnyViewReceiveForged(x, c) == ReceiveForgedBy(AnyView, x, c)

MutantNext ==
    \/ LElectionNext
    \/ \E n, m \in Nodes : SuspectLeft(n, m)
    \/ \E x \in Nodes, c \in forged : AnyViewReceiveForged(x, c)
    \/ LiarNext
    \/ LEnvironmentNext

MutantSpec == LInit /\ [][MutantNext]_allVars
=============================================================================
