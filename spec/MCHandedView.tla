---------------------------- MODULE MCHandedView ----------------------------
(***************************************************************************)
(* The models of HandedView: MCValueFault's cluster (MCValueFault.tla:     *)
(* PN1, PN2, PN3 in succession, ST1, IF1; t1, essential, on PN3 in P1 and  *)
(* PN2 in P2), its liar PN1, the first Master, which may also hand epoch 2 *)
(* to PN2 (MCHandedView.cfg, CI: MaxEpoch 2) or, in MCHandedViewThree.cfg  *)
(* (bench: MaxEpoch 3), epoch 3 to PN3 too, with any valid copy per        *)
(* receiver, switch numbers up to 1 (the liar's own Commands; no skipped  *)
(* number, which ValueFault's models cover), one phase change, no task     *)
(* step. Checks ValueFault's (a), (b),                                     *)
(* (c), (e) with hand-overs, NoHonestRefusalInv among them, under          *)
(* MCViewNoGhosts (its reduction holds here as well: a hand-over, like any *)
(* Command, is adopted only when newer, and the liar's are constants).     *)
(* The mutant HandedViewEdge runs it with the edge binding at seq 0 of     *)
(* every epoch (seed 15049).                                               *)
(***************************************************************************)
EXTENDS MCValueFault, HandedView

(***************************************************************************)
(* Witness: an invariant TLC must find violated (manifest "witnesses").    *)
(***************************************************************************)
\* The rule binds: a correct node n holds a handed copy of epoch e, and the boot switch of
\* e's Master, correct (it declared no one, so it did not take over: its seq 1 is its boot
\* switch), follows no edge from n's copy (the copies differ), is on its way to n and passes
\* n's checks (rule 3 and rule 5): n may take it, where the edge rule would have it declare
\* its Master failed (seed 15049).
WitnessHandedBootInv ==
    \A n \in Followers, msg \in msgs :
        ~(/\ msg.kind = "Command" /\ msg.view.seq = 1 /\ declared[msg.from] = {}
          /\ IsHanded(view[n]) /\ view[n].epoch = msg.view.epoch
          /\ ~HEdge(view[n], msg.view)
          /\ HChecked(n, msg.view) /\ Backed(n, msg.from, msg.view))
=============================================================================
