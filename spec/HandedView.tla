----------------------------- MODULE HandedView -----------------------------
(***************************************************************************)
(* Fault model 3 at a hand-over: a handed view is no edge source           *)
(* (docs/fault-model.md, prototype3 seed 15049). The module extends        *)
(* ValueFault (its nodes, views, receiver rules 1 to 5, correct Masters    *)
(* and properties) with the liar's hand-overs and the new Master's boot    *)
(* switch.                                                                 *)
(*                                                                         *)
(* A hand-over (NodeProtocol::handle_command, ReconfigurationManager::     *)
(* hand_over): the Master of a node's view gives the next epoch's first    *)
(* view to the node that epoch belongs to. Its Command is of epoch e, seq  *)
(* 0, names e's owner r its master, and comes from the Master of the       *)
(* receiver's view, not from r: the one Command whose sender is not the    *)
(* master it names. The liar, as Master, hands its view over to a correct  *)
(* node r with a different copy per receiver, any valid one                *)
(* (LiarHandOvers, on the wire from the start: each receiver may take any  *)
(* of them, so copies differ). A receiver takes one that passes its checks *)
(* (HandOverFrom: from the Master of its view, within a lap of the         *)
(* succession above its epoch, not excluding the receiver, ElectionLiar's  *)
(* rule 1; then rules 3 and 5 as any Command). r adopts its own copy and,  *)
(* as the new Master, makes its boot switch (BootSwitch;                   *)
(* ReconfigurationManager::boot_switch): the same configuration and        *)
(* failed set at seq 1, true to its copy, before any other switch.         *)
(*                                                                         *)
(* Rule 3 binds the next switch of a receiver's view to the graph's edge   *)
(* only when the view is one its master commanded itself (seq 1 on) or     *)
(* the initial one (epoch 1, seq 0, which no Command writes), and the      *)
(* switch is from that master (ValueFault's IsNextSwitch; the runtime's    *)
(* condition in NodeProtocol::command_problem). A handed view is written   *)
(* by the Master before, and a lying one may have sent this receiver a     *)
(* copy unlike the successor's: the successor's boot switch, true to its   *)
(* own copy, is no proof against it. Its first switch is held to a view    *)
(* the graph places (Valid), as one that skips a switch number is. The     *)
(* edge here is the runtime's edge_problem, which also takes the same      *)
(* configuration and failed set again (HEdge): a boot switch is one, so a  *)
(* correct Master now sends it (ValueFault's correct Masters send none).   *)
(*                                                                         *)
(* Properties: ValueFault's, with hand-overs. NoHonestRefusalInv is the    *)
(* one the rule is for: no correct node refuses a correct Master's         *)
(* Command, so none declares a correct node failed.                        *)
(*                                                                         *)
(* What TLC shows (MCHandedView.tla; one worker): every property holds     *)
(* with the liar, the first Master, handing epoch 2 to PN2 with any valid  *)
(* copy per receiver (MCHandedView, CI: 15,549 states), or epoch 2 to PN2  *)
(* or epoch 3 to PN3 (MCHandedViewThree, bench: 25,149 states, about 30    *)
(* CPU-seconds). With the edge binding at seq 0 of every epoch too (the    *)
(* code before seed 15049's fix; mutant HandedViewEdge) NoHonestRefusalInv *)
(* fails in 5 states: PN1 hands PN2 safe mode and PN3 P1 without PN1, both *)
(* (2, 0); PN2's boot switch (2, 1) into safe mode follows no edge from    *)
(* PN3's copy, and PN3 refuses it and declares PN2, a correct Master,      *)
(* failed. The same mutant fails as soon when PN2 takes over epoch 2 from  *)
(* the liar (on a Command of its it refused) while PN3 holds the liar's    *)
(* handed (2, 0): the take-over's view is the next switch of that copy     *)
(* too, and no edge from it. The witness WitnessHandedBootInv: a correct   *)
(* node holds a handed copy unlike its successor's, and the successor's    *)
(* boot switch, which follows no edge from that copy, is on its way to it  *)
(* and passes every check (4 states).                                      *)
(*                                                                         *)
(* Abstractions, beyond ValueFault's: the receivers are the correct        *)
(* processing nodes (seed 15049's receiver was the Storage node, whose     *)
(* view ValueFault does not model; PN3 plays its part). No correct Master  *)
(* hands over (ValueFault has no readmission; MasterElection.tla and       *)
(* ElectionLiar.tla model honest hand-overs and their repeats), and a      *)
(* hand-over names no boot (no node restarts here). The liar's invalid     *)
(* hand-overs are left out: rule 3 refuses them as any invalid view of     *)
(* its, which LiarCommands already has. The new Master boots at once: the  *)
(* runtime waits for fresh acknowledgements of its lease (Lease.tla).      *)
(***************************************************************************)
EXTENDS ValueFault

\* The liar's hand-overs: views (e, 0) naming e's owner, a correct node, their master, any
\* valid one; each receiver may take a different copy.
LiarHandOvers ==
    TLCEval({v \in [epoch : 1..MaxEpoch, seq : {0}, config : KnownConfigs,
                    master : Followers, failed : SUBSET ProcessingNodes] :
                Owner(v.epoch) = v.master /\ Valid(v)})

\* Rule 2 for a hand-over: node n takes view v, of seq 0 and naming its epoch's owner, from
\* s, the Master of n's view, which is not the master v names; within a lap of the
\* succession above n's epoch, and never a view that excludes n (ElectionLiar's rule 1,
\* KeepsReceiver: dropped, no evidence).
HandOverFrom(n, s, v) ==
    /\ v.seq = 0
    /\ v.master # s
    /\ Owner(v.epoch) = v.master
    /\ s = view[n].master
    /\ n \notin v.failed
    /\ view[n].epoch <= v.epoch
    /\ v.epoch <= view[n].epoch + N
HMayCommand(n, s, v) == MayCommand(n, s, v) \/ HandOverFrom(n, s, v)

\* Rule 3 with the runtime's edge (edge_problem): the same configuration and failed set
\* again is an edge too. HeldOp says which next switch is held to the edge (a mutant passes
\* another).
HEdge(w, v) == Edge(w, v) \/ (v.config = w.config /\ v.failed = w.failed)
HCheckedBy(HeldOp(_, _), n, v) == Valid(v) /\ (HeldOp(n, v) => HEdge(view[n], v))
HChecked(n, v) == HCheckedBy(IsNextSwitch, n, v)

\* Master m, handed its view, makes its boot switch: the same configuration and failed set
\* at seq 1 (ReconfigurationManager::boot_switch), before any other switch.
BootSwitch(m) ==
    /\ IsMaster(m)
    /\ IsHanded(view[m])
    /\ masterStage[m] = "Idle"
    /\ StartSwitch(m, [view[m] EXCEPT !.seq = 1])
    /\ UNCHANGED <<active, unflushed, version, fromLiar, declared, vetted, stored,
                   storedByLiar, honestStored, acks, writes, phaseChanges, steps,
                   lineageVars>>

\* ValueFault's next-state relation with the hand-over's authority and the given rule 3,
\* the liar's hand-overs and the boot switch. (The hand-over's steps come first: TLC then
\* reports, among the shortest counterexamples, seed 15049's story.)
HNextBy(CheckedOp(_, _)) ==
    \/ \E n \in Followers, v \in LiarHandOvers :
          ReceiveCommand(EpochInBounds, HMayCommand, CheckedOp, Backed, n, Liar, v)
    \/ \E m \in Followers : BootSwitch(m)
    \/ NextLineageBy(EpochInBounds, VersionInBounds, HMayCommand, CheckedOp, MayActivate,
                     MayAck, MayReply, MayWrite, PeersPrepared, Backed, WriteInEpoch,
                     ReplyInEpoch, RunLineage, Adoptable)

HNext == HNextBy(HChecked)

HSpec == Init /\ [][HNext]_vars
=============================================================================
