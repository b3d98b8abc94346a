------------------------------ MODULE PassOver ------------------------------
(***************************************************************************)
(* The pass-over of a member behind (docs/fault-model.md; keel-sim --liar  *)
(* --loss 5%, prototype3 seed 826, and an honest lossy run,                *)
(* earth-observation seed 11501 --loss 5%). The module extends             *)
(* ElectionLiar for the runtime's take-over guard (DeclaredGone), rule (2) *)
(* (SuspectLeft: a Master that left its view) and Reclaim, with no liar:   *)
(* `lying` is FALSE from the start (PInit), so ElectionLiar's liar forges  *)
(* nothing and acts as any node. The stories need no lie, only a Command   *)
(* or hand-over a node misses for good; the module adds that loss, the     *)
(* pass-over and the history its properties read.                          *)
(*                                                                         *)
(* Loss for good (PCrash): a Master repeats its Command until its          *)
(* receivers follow it, so a running Master's Command arrives in the end   *)
(* (MasterElection's fairness). The copies of a node that crashes are      *)
(* lost, or some are in flight and arrive: its crash may drop every        *)
(* Command and hand-over it sent that is still undelivered (`drop`), and a *)
(* node that missed them stays in the epoch before. In seed 826 PN3 handed *)
(* PN1 epoch 7, PN2 missed it, and PN1 went away; in seed 11501 PN3 missed *)
(* PN2's take-over of epoch 2, and PN2 crashed.                            *)
(*                                                                         *)
(* The rule (NodeProtocol::diverged_members, time_pass_over, diverged;     *)
(* Election::ahead_all_suspected(view, passed)). An Observer n takes over  *)
(* once the Master of its view is declared (DeclaredGone) and every node   *)
(* ahead of it in the view's succession (Ahead(n)) is declared or passed   *)
(* over. A member x is passed over (Behind) when it is an Observer of n's  *)
(* view, not its Master, not excluded (fenced), and says an epoch above 0  *)
(* and below n's (it never took the view: it missed the Command or         *)
(* hand-over that made it, and the Master that would repeat it is gone),   *)
(* and n hears it and it acknowledges n's heartbeats (it runs and n does   *)
(* not hold it failed; no node here is deaf). x goes by an older view,     *)
(* another succession, in which it may be a Worker that never takes over.  *)
(* A passed member counts as replaced by the take-over: it needs no        *)
(* declaration, and it adopts the new Master's epoch from its Command as   *)
(* any node does.                                                          *)
(*                                                                         *)
(* The wait, abstracted. The runtime passes over only 2 miss_limit periods *)
(* after the first tick at which only such members stand between n and a   *)
(* take-over, so that a member that is an Observer in its own older view   *)
(* may take over first and end the divergence. The spec has no time. (i)   *)
(* Once the guard holds the pass-over is enabled, and so is the member's   *)
(* own take-over when its view allows it, in either order; both may        *)
(* happen: two take-overs at once, each opening an epoch its taker owns,   *)
(* and the Master of the older steps down on the newer one's Command (seed *)
(* 11501). (ii) A member is passed over only while no Command above its    *)
(* epoch is on its way to it, nor a hand-over it could take (as            *)
(* ElectionLiar's SuspectLeft waits): the runtime declares a silent Master *)
(* after miss_limit periods and waits 2 miss_limit more, and a message     *)
(* arrives within a third of a period, or never. Liveness takes the        *)
(* pass-over as weakly fair as any take-over: the wait ends.               *)
(*                                                                         *)
(* Abstracted from the runtime besides: evidence is n's own declaration    *)
(* (the runtime needs two monitors' evidence, Exclusion.tla, and a passed  *)
(* member is no member of that quorum); "acknowledges n's heartbeats" is   *)
(* "runs"; a view is its epoch, so kind A (a member whose Prepared names   *)
(* another view under the view's id, a liar's doing) is not modelled; the  *)
(* take-over's epoch is ElectionLiar's (TakeOverFloor): TakeOverEpoch's    *)
(* voter rule and lease are that spec's (a passed member follows an epoch  *)
(* below the view's, which no take-over moves past).                       *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - MasterElection's OneMasterPerEpochInv, MasterOwnsEpochInv,           *)
(*    NoStaleMastershipInv, EpochMonotoneProp, StaleCommandRejectedProp.   *)
(*  - OneTakeOverPerViewInv: no two running Masters took over from one     *)
(*    view (epoch) but when one holds the other failed. The succession     *)
(*    answers the loss of a view's Master with one take-over: the first    *)
(*    node of the succession that runs takes over, and the nodes behind it *)
(*    follow it rather than take over beside it (two Masters at once, and  *)
(*    a failover more). A pass-over makes two take-overs at once only from *)
(*    two views: the member passed over goes by an older one. A            *)
(*    declaration, right or false, lets a node take over beside the one it *)
(*    declared; a pass-over of a member that follows the view does the     *)
(*    same with no declaration (mutant PassOverAtViewEpoch), and so does   *)
(*    one that does not wait for the Command on its way to the member      *)
(*    (mutant PassOverInFlight).                                           *)
(*  - PassOverLiveness: under fairness, if some node runs for good,        *)
(*    eventually, for good, one running Master leads every running node in *)
(*    its epoch (ElectionLiar's Agreed). Faults are bounded, so they stop. *)
(*                                                                         *)
(* What TLC shows (MCPassOver.tla has the models; one worker): the paper's *)
(* prototype with a fourth node, so that a view has a Worker (PN1..PN4,    *)
(* two Observers); no restart, no false declaration.                       *)
(*  - MCPassOver (one hand-over, one crash): 10,757 states, no violation.  *)
(*    Without the pass-over (mutant PassOverNone) TLC finds seed 826 on    *)
(*    four nodes (10,117 states): PN1 hands PN3 epoch 3, PN3 takes it and  *)
(*    commands, PN2 follows, and PN3 crashes, its Command to PN4 lost.     *)
(*    PN1, an Observer of epoch 3 behind PN4, declares PN3 and waits for   *)
(*    ever for PN4, which it hears; PN4 runs as a Worker of epoch 1 and    *)
(*    never takes over; PN2, a Worker of epoch 3, waits for PN4 and PN1:   *)
(*    no Master ever again (WitnessStrandedInv: that set-up). Passing over *)
(*    a member at the view's epoch too (mutant PassOverAtViewEpoch): PN1   *)
(*    hands PN3 epoch 3, PN2 and PN3, Observers of epoch 1, declare PN1    *)
(*    left, and PN3 passes PN2 over: both take over from epoch 1.          *)
(*    WitnessPassOverInv: a take-over passed over a member behind (PN3     *)
(*    crashes before taking its hand-over; PN1, in epoch 3, passes over    *)
(*    PN4, in epoch 1, and takes over epoch 5), and every running node     *)
(*    follows it.                                                          *)
(*  - MCPassOverCrashes (two crashes, no hand-over): 1,313 states, no      *)
(*    violation; seed 11501: PN1 crashes, PN2 takes over epoch 2 and       *)
(*    crashes, its Command to PN3 lost; PN4 passes PN3 over while PN3      *)
(*    takes over from epoch 1 (WitnessTwoTakeOversInv: both run as         *)
(*    Masters). Here no pass-over is needed (PassOverNone holds: 1,273     *)
(*    states): PN3 is an Observer in its own view. Without the wait for a  *)
(*    Command on its way (mutant PassOverInFlight) PN4 passes PN3 over     *)
(*    while PN2's Command of epoch 2 is still on its way to PN3; PN3 takes *)
(*    it, is an Observer of epoch 2 ahead of PN4, and takes over from      *)
(*    epoch 2 as well.                                                     *)
(*                                                                         *)
(* Not covered (stated, not hidden): a false declaration. With one         *)
(* (MCPassOver, MaxFalseSuspicions = 1) TLC finds OneTakeOverPerViewInv    *)
(* violated (57,540 states): PN1 falsely declares PN3 and hands it epoch   *)
(* 3, which PN3 takes; PN1 passes over PN4, which PN3 has not commanded    *)
(* yet, and takes over from epoch 3; PN3 commands, PN4 follows epoch 3,    *)
(* PN3 crashes, and PN4, ahead of PN1 in epoch 3's succession, takes over  *)
(* from it too. The pass-over turns a false declaration of the view's      *)
(* running Master into a take-over that the member ahead would otherwise   *)
(* have stood in the way of; in the runtime the wait makes it need the     *)
(* Master's Commands to that member lost for 2 miss_limit periods as well. *)
(* The safety properties of MasterElection hold there (231,537 states,     *)
(* PSpec), and PassOverLiveness fails for a reason the pass-over does not  *)
(* touch: PN3 falsely declares PN2, PN1 hands PN2 epoch 2, PN3 declares    *)
(* PN1 left and takes over epoch 3, PN2 follows it (its hand-over now      *)
(* stale), and PN3 crashes, its Commands to PN1 and PN4 lost: PN1, PN2 and *)
(* PN4 run as Workers of epochs 2, 3 and 1, and a Worker neither declares  *)
(* a Master left nor takes over. Nor a restart: with one (MaxRestarts = 1; *)
(* 25,536 states) PassOverLiveness fails for a reason outside the          *)
(* pass-over too: PN1 hands PN4 epoch 4 and crashes, the hand-over lost;   *)
(* PN1 restarts in epoch 4, its own, and waits to be commanded; PN2 takes  *)
(* over epoch 2, whose Commands are stale for PN1, and no Master moves     *)
(* past epoch 4, whose owner runs (Reclaim). A hand-over lost for good is  *)
(* this module's loss; the other models deliver it in the end.             *)
(***************************************************************************)
EXTENDS ElectionLiar

VARIABLES
    passedOver, \* history: a take-over passed over a member ahead that was behind
    takenFrom   \* history: [Nodes -> Nat], the epoch the node last took over from (0: its
                \* mastership, if any, is a hand-over's or a warm boot's)

passVars == <<allVars, passedOver, takenFrom>>

PTypeOK ==
    /\ LTypeOK
    /\ passedOver \in BOOLEAN
    /\ takenFrom \in [Nodes -> Nat]

\* MasterElection's initial state, with ElectionLiar's liar silent from the start.
PInit ==
    /\ Init
    /\ forged = {}
    /\ lying = FALSE
    /\ fencedByHandOver = [n \in Nodes |-> FALSE]
    /\ leftTakeOver = FALSE
    /\ behindTakeOver = FALSE
    /\ passedOver = FALSE
    /\ takenFrom = [n \in Nodes |-> 0]

(***************************************************************************)
(* The pass-over                                                           *)
(***************************************************************************)

\* x, ahead of n, is behind (NodeProtocol::diverged_members): an Observer of n's view, not
\* its Master (succeeded only on evidence), not excluded, that says an epoch above 0 and
\* below n's (its heartbeats say the highest epoch it adopted), heard by n and acknowledging
\* n's heartbeats (it runs, and n does not hold it failed); and, for the runtime's wait
\* (time_pass_over: 2 miss_limit periods after the Master was declared, which no message's
\* delay outlasts), no Command above its epoch is on its way to it, nor a hand-over it
\* could take (ElectionLiar's NoHandOverTo).
Behind(n, x) ==
    /\ x \in ObserversOf(epoch[n])
    /\ x # Owner(epoch[n])
    /\ ~fenced[x]
    /\ epoch[x] >= 1
    /\ epoch[x] < epoch[n]
    /\ alive[x]
    /\ x \notin suspects[n]
    /\ \A c \in msgs : c.epoch <= epoch[x]
    /\ NoHandOverTo(x)

\* The members ahead of n that an Observer n passes over, by the rule PassBy(n, x).
PassedBy(PassBy(_, _), n) ==
    IF role[n] = "Observer" THEN {x \in Ahead(n) \ suspects[n] : PassBy(n, x)} ELSE {}

Passed(n) == PassedBy(Behind, n)

\* ElectionLiar's take-over (LBecomeMaster: its guard the runtime's, its epoch the first n
\* owns above TakeOverFloor(n)) with every node ahead declared or passed over
\* (Election::ahead_all_suspected(view, passed)), by the rule PassBy, a parameter so that
\* a mutant changes it. takenFrom records the epoch taken over from.
TakeOverBy(PassBy(_, _), n) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] # "Master"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ DeclaredGone(n)
    /\ Ahead(n) \subseteq suspects[n] \cup PassedBy(PassBy, n)
    /\ LET e == NextEpochAbove(n, TakeOverFloor(n)) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ passedOver' = (passedOver \/ PassedBy(PassBy, n) # {})
    /\ takenFrom' = [takenFrom EXCEPT ![n] = epoch[n]]
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED liarVars

TakeOver(n) == TakeOverBy(Behind, n)

(***************************************************************************)
(* Loss for good                                                           *)
(***************************************************************************)

\* MasterElection's crash (the last node down takes every message with it); with `drop`,
\* the Commands and hand-overs the node sent that are still undelivered are lost: no one
\* repeats them. A node that missed them stays in the epoch before.
PCrash(n, drop) ==
    /\ alive[n]
    /\ crashes < MaxCrashes
    /\ alive' = [alive EXCEPT ![n] = FALSE]
    /\ crashes' = crashes + 1
    /\ LET last == \A x \in Nodes \ {n} : ~alive[x] IN
        /\ msgs' = IF last THEN {}
                   ELSE IF drop THEN {c \in msgs : c.from # n} ELSE msgs
        /\ handOvers' = IF last THEN {}
                        ELSE IF drop THEN {h \in handOvers : h.from # n} ELSE handOvers
    /\ UNCHANGED <<role, epoch, leader, suspects, lastCommand, boot, restartEpoch, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED liarVars
    /\ UNCHANGED <<passedOver, takenFrom>>

(***************************************************************************)
(* Next state and fairness                                                 *)
(***************************************************************************)

\* ElectionLiar's steps (each by a node that does not lie, the liar being silent), leaving
\* the history alone; a node made Master by a hand-over or a warm boot took over from no
\* view.
PSuspect(n, m) == LSuspect(n, m) /\ UNCHANGED <<passedOver, takenFrom>>
PSuspectFenced(n, m) == LSuspectFenced(n, m) /\ UNCHANGED <<passedOver, takenFrom>>
PSuspectLeft(n, m) == SuspectLeft(n, m) /\ UNCHANGED <<passedOver, takenFrom>>
PReclaim(n, above) == Reclaim(n, above) /\ UNCHANGED <<passedOver, takenFrom>>
PWarmBoot(n) ==
    LWarmBoot(n) /\ takenFrom' = [takenFrom EXCEPT ![n] = 0] /\ UNCHANGED passedOver
PBroadcastCommand(n) == LBroadcastCommand(n) /\ UNCHANGED <<passedOver, takenFrom>>
PReceiveCommand(n, msg) == LReceiveCommand(n, msg) /\ UNCHANGED <<passedOver, takenFrom>>
PHandOver(m, r) == LHandOver(m, r) /\ UNCHANGED <<passedOver, takenFrom>>
PTakeHandOver(r, h) ==
    LTakeHandOver(r, h) /\ takenFrom' = [takenFrom EXCEPT ![r] = 0] /\ UNCHANGED passedOver
PFence(m, n) == LFence(m, n) /\ UNCHANGED <<passedOver, takenFrom>>
PReadmit(m, n) == LReadmit(m, n) /\ UNCHANGED <<passedOver, takenFrom>>
PRestart(n) == LRestart(n) /\ UNCHANGED <<passedOver, takenFrom>>

\* Every step but the take-over, which PNext and a mutant's next-state relation add.
PNextBut ==
    \/ \E n, m \in Nodes : PSuspect(n, m)
    \/ \E n, m \in Nodes : PSuspectFenced(n, m)
    \/ \E n, m \in Nodes : PSuspectLeft(n, m)
    \/ \E n \in Nodes, e \in {epoch[x] : x \in Nodes} : PReclaim(n, e)
    \/ \E n \in Nodes : PWarmBoot(n)
    \/ \E n \in Nodes : PBroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : PReceiveCommand(n, msg)
    \/ \E m, r \in Nodes : PHandOver(m, r)
    \/ \E r \in Nodes, h \in handOvers : PTakeHandOver(r, h)
    \/ \E m, n \in Nodes : PFence(m, n)
    \/ \E m, n \in Nodes : PReadmit(m, n)
    \/ \E n \in Nodes, drop \in BOOLEAN : PCrash(n, drop)
    \/ \E n \in Nodes : PRestart(n)

\* ElectionLiar's fairness (LFairness), all but the take-over's, which PFairSpec and a
\* mutant's spec add. A Master need not hand over, fence nor readmit.
PFairnessBut ==
    /\ \A n, m \in Nodes : WF_passVars(~alive[m] /\ PSuspect(n, m))
    /\ \A n, m \in Nodes : WF_passVars(PSuspectFenced(n, m))
    /\ \A n, m \in Nodes : WF_passVars(PSuspectLeft(n, m))
    /\ \A n \in Nodes : WF_passVars(\E e \in {epoch[x] : x \in Nodes} : PReclaim(n, e))
    /\ WF_passVars(\E n \in Nodes : PWarmBoot(n))
    /\ \A n \in Nodes : WF_passVars(PBroadcastCommand(n))
    /\ \A n \in Nodes : WF_passVars(\E msg \in msgs : PReceiveCommand(n, msg))
    /\ \A r \in Nodes : WF_passVars(\E h \in handOvers : PTakeHandOver(r, h))

PNext == PNextBut \/ \E n \in Nodes : TakeOver(n)
PSpec == PInit /\ [][PNext]_passVars
PFairSpec == PSpec /\ PFairnessBut /\ \A n \in Nodes : WF_passVars(TakeOver(n))

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No two running Masters took over from the same view (epoch) but when one holds the other
\* failed: the first node of its succession that runs takes over, and the others follow it.
OneTakeOverPerViewInv ==
    \A n, m \in Nodes :
        (/\ n # m
         /\ alive[n] /\ alive[m]
         /\ role[n] = "Master" /\ role[m] = "Master"
         /\ takenFrom[n] # 0
         /\ takenFrom[n] = takenFrom[m])
        => n \in suspects[m] \/ m \in suspects[n]

\* Under fairness, if some node runs for good, eventually, for good, one running Master
\* leads every running node in its epoch (ElectionLiar's Agreed).
PassOverLiveness == (\E n \in Nodes : <>[]alive[n]) => <>[]Agreed

=============================================================================
