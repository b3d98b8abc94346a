---------------------------- MODULE MCValueFault ----------------------------
(***************************************************************************)
(* Models of ValueFault for CI, one per kind of liar: MCValueFault.cfg     *)
(* (PN1, the first Master, lies), MCValueFaultRegression.cfg (the same,    *)
(* with a task PN1 may not host), MCValueFaultObserver.cfg (PN2, the       *)
(* higher-priority Observer), MCValueFaultStorage.cfg (the Storage node    *)
(* ST1) and MCValueFaultInterface.cfg (the interface node IF1, which owns  *)
(* no epoch, stores nothing and may host no task); two with lineages,      *)
(* MCValueFaultLineage.cfg (PN2) and MCValueFaultLineageStorage.cfg (ST1); *)
(* and MCValueFaultWidth.cfg (PN3, a Worker that may host t1), for counts  *)
(* at the codec's width.                                                   *)
(*                                                                         *)
(* The paper's prototype with the Earth-observation mission's interface    *)
(* node: PN1, PN2, PN3 in succession, ST1, IF1; checkpointed tasks. t1 is  *)
(* essential (safe mode runs it on the master, so every processing node    *)
(* may host it). A configuration is a phase and the processing node the    *)
(* graph took out (at most one; a second failure leads to Safe); its       *)
(* master is PN1, or PN2 once PN1 is out; t1 runs on PN3 in P1 and on PN2  *)
(* in P2, on the other of the two when that one is out. The phase change   *)
(* swaps t1 between PN2 and PN3 (the double-activation case). A second     *)
(* task, t2, not essential, runs the other way round (PN2 in P1, PN3 in    *)
(* P2): only PN2 and PN3 may host it. MCValueFaultRegression,              *)
(* MCValueFaultStorage, MCValueFaultInterface and                          *)
(* MCValueFaultLineageStorage run both, crosswise; MCValueFault,           *)
(* MCValueFaultObserver and MCValueFaultWidth only t1, MCValueFaultLineage *)
(* only t2.                                                                *)
(*                                                                         *)
(*  - MCValueFault: PN1 lies as Master of epoch 1 (MaxEpoch 3: its next    *)
(*    owned epoch, 4, is beyond the wire), with switch numbers up to 2 (it *)
(*    may skip one), MaxVersion 0 and no task step (MaxSteps 0: no         *)
(*    property checked here reads versions). PN2 refuses a bad Command and *)
(*    takes over in epoch 2; PN3 may follow the liar's views meanwhile,    *)
(*    and follows PN2 once it refused a bad Command too (rule 5); the liar *)
(*    may fence either (a view excluding it, followed unchecked). Checks   *)
(*    (a), (b), (c), (e). The mutant ValueFaultFencedThenUnchecked runs it *)
(*    with switch numbers up to 3: fencing a node and then readmitting it  *)
(*    takes a skipped number.                                              *)
(*  - MCValueFaultRegression: MCValueFault with t2, which PN1 may not      *)
(*    host, one step of each task (MaxSteps 1, MaxVersion 2: the adoption  *)
(*    bound is 1), switch numbers up to 1, and the liar's checkpoint       *)
(*    messages carrying count 0 or one beyond the width (MCLiarVersions    *)
(*    below): the model in which (d) fails without rules 4 and 5           *)
(*    (ValueFault's header). Checks (a) to (e).                            *)
(*  - MCValueFaultObserver: PN2 lies; PN1 is the correct Master. PN2's     *)
(*    views of epoch 2 are followed (by PN1 too, which steps down), its    *)
(*    bad ones refused: PN1 excludes it on that evidence, PN3 takes over   *)
(*    in epoch 3 from a view of PN2's. MaxEpoch 4, switch numbers up to 1, *)
(*    no task step. Checks (a), (b), (c), (e).                             *)
(*  - MCValueFaultStorage and MCValueFaultInterface: PN1 the correct       *)
(*    Master, two phase changes, a step of each task (MaxSteps 1,          *)
(*    MaxVersion 2: the adoption bound is 1). None of the liar's Commands  *)
(*    or Activates has authority; ST1's checkpoint acknowledgements and    *)
(*    restore replies do (it is the Storage node): a reply of a count at   *)
(*    the width, above the adoption bound, is taken as lost, and its       *)
(*    receiver starts from no state in a lineage of its view. IF1's do     *)
(*    not. Check (a), (b), (c), (e), and in MCValueFaultInterface (d).     *)
(*  - MCValueFaultLineage: PN2 lies, with lineages; PN1 is the correct     *)
(*    Master, two phase changes, MaxEpoch 2, switch numbers up to 1,       *)
(*    MaxVersion 0 and no task step, one task, t2 (no essential task),     *)
(*    which PN2 may host: PN2 hosts it in P1, PN3 in P2. PN2's checkpoint  *)
(*    messages carry the initial lineage or one of its epoch 2, and it     *)
(*    sends only Commands without a defect (LiarCommands <-                *)
(*    MCValidLiarCommands). The Storage node may follow PN2's epoch 2      *)
(*    before PN3 does. Checks (a), (b), (c), (e), (f) with FlushLiveness   *)
(*    (SPECIFICATION LineageSpec).                                         *)
(*  - MCValueFaultLineageStorage: MCValueFaultStorage with lineages and no *)
(*    task step (MaxVersion 1, MaxSteps 0): ST1's acknowledgements and     *)
(*    restore replies carry the initial lineage or one of epoch 3, which   *)
(*    no node adopts (seed 12602). Checks (a), (b), (c), (e) and           *)
(*    NoFutureLineageInv ((f)'s other properties are about a correct       *)
(*    Storage node).                                                       *)
(*  - MCValueFaultWidth: PN3 lies, a Worker whose epoch, 3, is beyond the  *)
(*    wire (MaxEpoch 2): only its checkpoint messages have authority. It   *)
(*    may host t1, the one task (P1 places it on PN3, P2 on PN2), and its  *)
(*    checkpoint messages carry any count the wire does, the width among   *)
(*    them (MaxVersion 2, MaxSteps 1: the adoption bound is 1). PN1 is the *)
(*    correct Master, with two phase changes; the Storage node is correct. *)
(*    The protocol fuzzer's finding: without the adoption rule PN2         *)
(*    restores the liar's count at the width, steps past it, and its final *)
(*    flush is never acknowledged. Checks (a), (b), (c), (e), (f) with     *)
(*    FlushLiveness (SPECIFICATION LineageSpec).                           *)
(*                                                                         *)
(* Each model uses a VIEW, as MCConfigSwitch does: TLC tells states apart  *)
(* by what a step or a property can still read (MCView; MCViewNoGhosts in  *)
(* MCValueFault and MCValueFaultObserver, where nothing reads the ghosts). *)
(* MCView and MCViewNoGhosts leave out the lineages and the Storage node's *)
(* epoch: in their models every state stays in the initial lineage (the    *)
(* liar's lineages are the initial one, and no count the correct Storage   *)
(* node holds is above the adoption bound, so no start is taken as lost),  *)
(* so every write is within any epoch and nothing reads them. The models   *)
(* with lineages, and MCValueFaultWidth, use MCLineageView (below);        *)
(* MCValueFaultStorage, whose lying Storage node's replies above the bound *)
(* are lost starts, MCLineageGhostView.                                    *)
(***************************************************************************)
EXTENDS ValueFault

CONSTANTS PN1, PN2, PN3, ST1, IF1, t1, t2

MCPriority == <<PN1, PN2, PN3>>

\* The mission phases.
MCPhases == {"P1", "P2"}

\* A configuration is a phase and the processing node the graph took out (at most one);
\* a second failure leads to Safe.
MCConfigIds == [phase : MCPhases, out : {{}} \cup {{x} : x \in {PN1, PN2, PN3}}]
MCInitialConfig == [phase |-> "P1", out |-> {}]

\* The master: the first node in succession the configuration did not take out.
MCConfigMaster(c) == IF PN1 \notin c.out THEN PN1 ELSE PN2

\* Where a task runs: t1 on PN3 in P1 and on PN2 in P2, t2 the other way round; on the
\* other of the two if that one is out (a configuration takes out at most one node).
MCPreference(p, t) == IF (p = "P1") = (t = t1) THEN <<PN3, PN2>> ELSE <<PN2, PN3>>
MCHost(c, t) ==
    LET pref == MCPreference(c.phase, t)
    IN  IF pref[1] \notin c.out THEN pref[1] ELSE pref[2]

MCOnFailure(c, f) ==
    IF f \in c.out THEN c
    ELSE IF c.out = {} THEN [c EXCEPT !.out = {f}]
    ELSE Safe

MCOnPhase(c) ==
    IF c = Safe THEN {}
    ELSE {[c EXCEPT !.phase = IF @ = "P1" THEN "P2" ELSE "P1"]}

(***************************************************************************)
(* Reduction: MCView, the VIEW of the models. States that differ only in   *)
(* what no step and no property reads again are one state; what is hidden, *)
(* and why no step reads it again:                                         *)
(*  - dead messages. A correct Master's Command is read only by a node     *)
(*    whose view is older (a view is adopted only when newer), its         *)
(*    Activate only by a node in that switch that has not activated yet    *)
(*    (every node its view does not exclude adopted it before the Master   *)
(*    sent the Activate, and it excludes only the liar); views only grow,  *)
(*    a switch's stage only advances. The liar's messages are constants,   *)
(*    not state.                                                           *)
(*  - dead acks. AllAcked reads only the acks of a correct Master's        *)
(*    current view, "Prepared" ones while it prepares; PeersPrepared only  *)
(*    the "Prepared" acks of a node's own view before it took its          *)
(*    Activate; Vouched only "Prepared" acks of a view newer than the      *)
(*    reader's. A node adopts only newer views, so a "Prepared" ack is     *)
(*    dead once no node is in its view before that view's Activate and     *)
(*    every node's view is at least as new.                                *)
(*  - dead writes: a final checkpoint write not newer than what the        *)
(*    Storage node holds (it keeps the newest).                            *)
(*  - the version of a task a node neither runs nor has to flush: Activate *)
(*    overwrites it before anything reads it.                              *)
(*                                                                         *)
(* MCViewNoGhosts also hides the ghosts fromLiar, storedByLiar and         *)
(* honestStored, which only NoRegressionInv and NoForeignStateInv read     *)
(* (and storedByLiar only to set fromLiar). Without a VIEW (by hand) no    *)
(* property fails either: MCValueFault 58,216 states, MCValueFaultObserver *)
(* 291,338, MCValueFaultRegression 97,000.                                 *)
(***************************************************************************)
\* A Command of a correct Master is read only by a node whose view is older; an Activate
\* only by a node in its switch that has not activated yet. Views only grow.
MCLiveMsg(msg) ==
    \E n \in Followers :
        IF msg.kind = "Command" THEN Newer(msg.view, view[n])
        ELSE /\ <<view[n].epoch, view[n].seq>> = <<msg.epoch, msg.seq>>
             /\ stage[n] \in {"Deactivating", "Prepared"}
\* An ack is read only by the correct Master of its view, while it waits for that kind; a
\* "Prepared" one also by a node in that view that has not taken its Activate yet, or by
\* one whose view is older, which may adopt that view later, or take the ack as a vouch.
MCLiveAck(a) ==
    \/ \E m \in Followers :
          /\ IsMaster(m)
          /\ view[m] = a.view
          /\ \/ masterStage[m] = "Preparing"
             \/ masterStage[m] = "Activating" /\ a.kind = "Activated"
    \/ /\ a.kind = "Prepared"
       /\ \E n \in Followers :
             \/ view[n] = a.view /\ stage[n] \in {"Deactivating", "Prepared"}
             \/ Newer(a.view, view[n])
\* A write is read only while it is newer than the checkpoint the Storage node holds.
MCLiveWrite(w) ==
    Storage # Liar /\ StateGt(w.lineage, w.version, storedLineage[w.task], stored[w.task])
\* The version of a task a node neither runs nor has to flush: Activate overwrites it.
MCVersions(n) == [t \in active[n] \cup unflushed[n] |-> <<version[n][t], fromLiar[n][t]>>]
MCView ==
    <<view, stage, active, unflushed, [n \in Followers |-> MCVersions(n)], declared, vetted,
      masterStage, stored, storedByLiar, honestStored,
      {msg \in msgs : MCLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      {w \in writes : MCLiveWrite(w)}, phaseChanges, steps>>
\* The same without the ghosts.
MCViewNoGhosts ==
    <<view, stage, active, unflushed,
      [n \in Followers |-> [t \in active[n] \cup unflushed[n] |-> version[n][t]]],
      declared, vetted, masterStage, stored,
      {msg \in msgs : MCLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      {w \in writes : MCLiveWrite(w)}, phaseChanges, steps>>

(***************************************************************************)
(* The models with lineages. Their liar's checkpoint messages carry the    *)
(* initial lineage or one of the widest epoch, MaxEpoch (MCLiarLineages):  *)
(* in MCValueFaultLineage that is the liar's own epoch, which no correct   *)
(* node but the Storage node may adopt, in MCValueFaultLineageStorage one  *)
(* no node adopts. In MCValueFaultLineage the liar sends only Commands     *)
(* without a defect (MCValidLiarCommands): a refused Command, and the      *)
(* exclusion it leads to, are the other models' business, and the lineage  *)
(* rules read no view but its epoch. Their VIEW, MCLineageView, is         *)
(* MCViewNoGhosts with the lineage of each state a step can still read     *)
(* (the Storage node's, and those of the tasks a node runs or has to       *)
(* flush), the Storage node's epoch, a correct Master's Command while the  *)
(* Storage node may still follow it, and, for a task a node runs, the      *)
(* lineage it started from (NoFutureStateInv reads it; Activate overwrites *)
(* it). MCValueFaultWidth uses it too: a start taken as lost opens a       *)
(* lineage of a view, and the Storage node's epoch decides whether a write *)
(* of it is taken.                                                         *)
(***************************************************************************)
MCLiarLineages == {InitialLineage, <<MaxEpoch, 1>>}
\* MCValueFaultRegression's liar: its checkpoint messages carry count 0, or one beyond the
\* width (dropped by rule 1). A count of its at the bound, which a correct node adopts and
\* steps past, is taken as lost by the next host, which starts in a lineage of its view: a
\* lineage MCView does not tell apart, and MCValueFaultWidth's business (t1, which the liar
\* may host; (d) is about t2).
MCLiarVersions == {0, MaxVersion + 1}
MCValidLiarCommands == TLCEval({v \in WireViews : Defects(v) = 0})
MCLineageStates(n) ==
    [t \in active[n] \cup unflushed[n] |->
        <<version[n][t], lineage[n][t],
          IF t \in active[n] THEN startLineage[n][t] ELSE InitialLineage>>]
\* A correct Master's Command is read by the Storage node too, while its epoch is newer.
MCLineageLiveMsg(msg) ==
    \/ MCLiveMsg(msg)
    \/ msg.kind = "Command" /\ Storage # Liar /\ msg.view.epoch > storeEpoch
MCLineageView ==
    <<view, stage, active, unflushed, [n \in Followers |-> MCLineageStates(n)],
      declared, vetted, masterStage, stored, storedLineage, storeEpoch,
      {msg \in msgs : MCLineageLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      {w \in writes : MCLiveWrite(w)}, phaseChanges, steps>>
\* The same with the ghosts (MCView's), for MCValueFaultStorage: its lying Storage node's
\* replies above the adoption bound are lost starts, in lineages of views.
MCLineageGhostView ==
    <<view, stage, active, unflushed,
      [n \in Followers |->
          [t \in active[n] \cup unflushed[n] |-> <<MCLineageStates(n)[t], fromLiar[n][t]>>]],
      declared, vetted, masterStage, stored, storedLineage, storeEpoch, storedByLiar,
      honestStored,
      {msg \in msgs : MCLineageLiveMsg(msg)}, {a \in acks : MCLiveAck(a)},
      {w \in writes : MCLiveWrite(w)}, phaseChanges, steps>>

(***************************************************************************)
(* Witnesses: each is an invariant TLC must find violated (manifest        *)
(* "witnesses"): the states the properties are about are reachable.        *)
(***************************************************************************)
\* A correct node refused a Command of the liar's and declared it failed (MCValueFault,
\* MCValueFaultObserver).
WitnessLiarRefusedInv == \A n \in Followers : Liar \notin declared[n]
\* A correct node runs as Master: it took over from the liar (MCValueFault), or from the
\* liar that had taken over (MCValueFaultObserver: PN3).
WitnessLiarDeposedInv == \A n \in Followers : IsMaster(n) => n = Priority[1]
\* A correct node follows a view the liar sent, one that passed every check.
WitnessLiarFollowedInv == \A n \in Followers : ~(view[n].master = Liar /\ view[n].seq > 0)
\* The configuration the graph reaches from phase p's first configuration when F fail.
MCGraphConfig(p, F) == Target([phase |-> p, out |-> {}], F, F)
\* A correct node follows a view of the liar's whose configuration is not the graph's for
\* its failed set in any phase: a switch that skipped a number, held to structural
\* validity only (MCValueFault).
WitnessLiarOffGraphInv ==
    \A n \in Followers :
        ~(/\ view[n].master = Liar
          /\ view[n].config \notin {MCGraphConfig(p, view[n].failed) : p \in MCPhases})
\* Rule 4 binds: a correct node prepared its switch and holds its Activate from the master
\* of its view, but not yet every peer's "Prepared" of that view (MCValueFault: the liar's
\* Activate of a phase change that PN3 has not received).
WitnessActivateHeldInv ==
    \A n \in Followers :
        ~(/\ stage[n] = "Prepared"
          /\ \/ view[n].master = Liar
             \/ ActivateMsg(view[n].master, view[n]) \in msgs
          /\ ~PeersPrepared(n))
\* Rule 5 lets a backed exclusion through: a correct node follows another correct node's
\* take-over, which excludes the liar, on a correct node's word (MCValueFault: PN3 follows
\* PN2's epoch 2 on its own declaration of PN1, made before, since no Command of epoch 1
\* is newer than epoch 2; the liar's request for its own exclusion would back it too).
WitnessBackedTakeOverInv ==
    \A n \in Followers :
        ~(view[n].master \notin {n, Liar} /\ Liar \in view[n].failed /\ Liar \in declared[n])
\* A correct node follows a view of the liar's that excludes it, unchecked by rule 5: the
\* liar fenced it (MCValueFault: PN1's next switch excluding PN2 or PN3, which no node
\* declared).
WitnessFencedByLiarInv ==
    \A n \in Followers : ~(view[n].master = Liar /\ n \in view[n].failed)
\* The first Master, correct, follows the liar's epoch: the liar took over with a valid
\* Command of an epoch it owns (MCValueFaultObserver).
WitnessMasterFollowsLiarInv ==
    \A n \in Followers : ~(n = Priority[1] /\ view[n].master = Liar)
\* A correct Master's view excludes the liar, on the evidence of a Command it refused
\* (MCValueFaultObserver: the first Master's Exclude).
WitnessLiarExcludedInv ==
    \A m \in Followers : ~(IsMaster(m) /\ view[m].epoch = 1 /\ Liar \in view[m].failed)
\* A task runs on a correct node restored from a checkpoint above version 0 that a correct
\* node wrote (MCValueFaultInterface: the premise of NoRegressionInv).
WitnessRestoreInv ==
    \A n \in Followers, t \in Tasks : ~(t \in active[n] /\ honestStored[t] > 0)
\* A task runs on a correct node restored from the lying Storage node's reply
\* (MCValueFaultStorage).
WitnessLiarStorageRestoreInv ==
    \A n \in Followers, t \in Tasks : ~(t \in active[n] /\ fromLiar[n][t])
\* Rule 2a binds on the liar (MCValueFaultLineage): a correct node activates a task it
\* restores from the correct Storage node, to which the liar wrote a newer state of a lineage
\* of an epoch the Storage node has not adopted; that write was dropped.
WitnessFutureWriteDroppedInv ==
    \A n \in Followers, t \in Tasks :
        ~(/\ Storage # Liar
          /\ stage[n] = "Activating" /\ PlacedOn(view[n], t) = n /\ t \notin active[n]
          /\ \E w \in LiarWrites :
                /\ w.task = t /\ VersionInBounds(w.version) /\ MayWrite(Liar, t)
                /\ LineageEpoch(w.lineage) > storeEpoch
                /\ StateGt(w.lineage, w.version, storedLineage[t], stored[t]))
\* Rule 2b binds (MCValueFaultLineage): a correct node activates a task the liar may
\* host, and the liar's reply holds a state of a lineage of an epoch no correct node has
\* adopted; the node takes another reply.
WitnessFutureReplyDroppedInv ==
    \A n \in Followers, t \in Tasks :
        ~(/\ stage[n] = "Activating" /\ PlacedOn(view[n], t) = n /\ t \notin active[n]
          /\ Liar \in MayHost(t)
          /\ \E l \in LiarLineages : LineageEpoch(l) > AdoptedEpoch)
\* The start rule binds: a correct node started a task from a state of a lineage of an
\* epoch above its view's, and runs it in its view's lineage (MCValueFaultLineage: from the
\* correct Storage node, which followed the liar's epoch 2 before the node did;
\* MCValueFaultLineageStorage: from the lying Storage node).
WitnessFutureStartInv ==
    \A n \in Followers, t \in Tasks :
        ~(t \in active[n] /\ LineageEpoch(startLineage[n][t]) > view[n].epoch)
\* The adoption rule binds on the Storage node's reply (MCValueFaultWidth): the correct
\* Storage node holds a state above the adoption bound (the liar's, at the width), and a
\* correct node runs the task from no state, count 0, in the lineage its view opened, newer
\* than that state (the liar's lineages being the initial one alone, only a lost start
\* opens one).
WitnessLostAboveBoundInv ==
    \A n \in Followers, t \in Tasks :
        ~(/\ Storage # Liar
          /\ t \in active[n] /\ version[n][t] = 0 /\ lineage[n][t] = ViewLineage(n)
          /\ stored[t] > AdoptBound
          /\ StateGt(lineage[n][t], 0, storedLineage[t], stored[t]))
\* A state adopted at the bound runs past it (MCValueFaultWidth): a correct node stopped a
\* task at a count above the adoption bound (no correct run makes one from no state: it
\* adopted the liar's at the bound and stepped), and its final flush, within the width, is
\* newer than the Storage node's checkpoint: the Storage node stores it (FlushLiveness).
WitnessPastBoundInv ==
    \A n \in Followers, t \in Tasks :
        ~(/\ Storage # Liar
          /\ t \in unflushed[n] /\ version[n][t] > AdoptBound
          /\ VersionInBounds(version[n][t])
          /\ StateGt(lineage[n][t], version[n][t], storedLineage[t], stored[t]))
=============================================================================
