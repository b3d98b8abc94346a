---------------------------- MODULE DivergedView ----------------------------
(***************************************************************************)
(* The pass-over of a member that goes by another view than the receiver's *)
(* own: one that prepared another view under the id of the receiver's, or  *)
(* a newer switch of its epoch (docs/fault-model.md, "A Master's two views *)
(* under one id left a correct Observer waiting for a Worker"; keel-sim    *)
(* --liar, prototype3 seed 30979). The module extends ElectionLiar for the *)
(* succession, the runtime's take-over guard (DeclaredGone), rule (2)      *)
(* (SuspectLeft), Reclaim and the liar's crash and honest restart, and     *)
(* adds what the election alone does not have: a view's id (its epoch and  *)
(* switch number, seq), its copy (the digest a Prepared names, and the     *)
(* Observers the copy says), the correct nodes' Prepared, and the liar's   *)
(* one lie here, a switch whose copies differ or miss nodes.               *)
(*                                                                         *)
(* The lie (ForgeSwitch). The liar, the Master of its own epoch e, makes a *)
(* switch (e, s+1), s >= 0 its view's seq, and sends each correct node a   *)
(* copy of its own (keel-sim's liar changes a Command's configuration per  *)
(* receiver), or, where a model lets it (LiarSwitchTo;                     *)
(* MCDivergedViewLost), some correct nodes only: a copy never sent, or     *)
(* lost for good when the liar crashes, leaves its node in the view it     *)
(* holds. A copy is one of the constant Copies: Std, the view an honest    *)
(* Master of e sends (its Observers ObserversOf(e)), or another, whose     *)
(* Observers CopyObservers names, in the succession's order: a copy may    *)
(* make a node a Worker that another copy makes the first Observer (S1 and *)
(* safe mode from P3 in seed 30979), or name the same Observers with       *)
(* another digest (a task placed elsewhere). A correct node adopts its     *)
(* copy when its id is newer than its view's (ReceiveSwitch; the runtime's *)
(* Command), takes the role the copy gives it, and sends its Prepared,     *)
(* which names the view (NodeProtocol: Ack{Prepared, epoch, seq,           *)
(* view_digest}); DDS binds each Prepared to its sender. The copies sent   *)
(* arrive before any node declares the liar (delays of a third of a        *)
(* period, detection after MissLimit periods): a node declares the liar    *)
(* only once no copy to a running correct node is still newer than that    *)
(* node's view (SwitchDelivered).                                          *)
(*                                                                         *)
(* The rule (NodeProtocol::note_divergence, diverged_members,              *)
(* time_pass_over, diverged, takeover_evidence, members_of;                *)
(* ConfigSwitch::prepared_newer_switch;                                    *)
(* Election::ahead_all_suspected(view, passed)). An Observer n takes over  *)
(* once the Master of its view is declared (DeclaredGone) and every        *)
(* Observer its copy places ahead of it (AheadIn) is declared or passed    *)
(* over. A member x that is not the view's Master (succeeded only on       *)
(* evidence) is passed over (Diverged) when                                *)
(*  - x prepared a view under n's view's id whose digest is not n's, n's   *)
(*    view having seq >= 1 (OtherCopy; not a hand-over's or the initial    *)
(*    view's seq 0: two Masters of different epochs may hand one successor *)
(*    the same epoch, so honest copies at seq 0 may differ). Only a Master *)
(*    that issued two views under one id (the liar here), or x's own lie,  *)
(*    makes one;                                                           *)
(*  - or x's newest Prepared names a switch of n's view's epoch newer than *)
(*    n's view, whatever its digest, at any seq of n's view, 0 too         *)
(*    (NewerSwitch): a newer switch of an epoch has one writer, the        *)
(*    epoch's Master, and x took one that never reached n (a copy the liar *)
(*    never sent to n here; in the runtime, a copy lost when the Master    *)
(*    crashed too).                                                        *)
(* Either way x goes by another view, another succession, in which it may  *)
(* be a Worker that never takes over. A passed member counts as declared   *)
(* for the guard, needs no evidence and is no member of the take-over's    *)
(* quorum (the spec has no quorum: n's own declaration is the evidence, as *)
(* in PassOver), and adopts the new Master's epoch from its Command as any *)
(* node does.                                                              *)
(*                                                                         *)
(* The wait, abstracted. The runtime passes over only 2 miss_limit periods *)
(* after the first tick at which only such members stand between n and a   *)
(* take-over, so that a member that is an Observer in its own copy takes   *)
(* over first and its Command ends the divergence, and only a member it    *)
(* hears and that acknowledges its heartbeats (one that excluded n in its  *)
(* newer view acknowledges it no more). A member passed over for a newer   *)
(* switch must besides no longer hear the Master of n's epoch (its         *)
(* heartbeats' acknowledgements of that Master's stopped moving, or name a *)
(* later incarnation: NodeProtocol::hears_master); modelled as MasterRuns, *)
(* the spec having no deafness. The runtime needs it for its quorum, which *)
(* a member passed over leaves (keel-sim prototype3 seed 12313: PN3, deaf  *)
(* to a live PN1, missed PN1's switch that PN2 took, passed PN2 over and   *)
(* took over alone); the spec has no quorum, so no property here fails     *)
(* without it (by hand), and the runtime's unit test                       *)
(* AMemberThatTookANewerSwitchAndStillHearsTheMasterIsNotPassedOver is its *)
(* check. The spec has no time, and neither                                *)
(* loss nor deafness here: once the guard holds the pass-over is enabled,  *)
(* and so is the member's own take-over when its copy allows it, in either *)
(* order; both may happen, each opening an epoch its taker owns (two       *)
(* take-overs from two views of one epoch), and the Master of the older    *)
(* epoch adopts the newer one's Command. Liveness takes the pass-over as   *)
(* weakly fair as any take-over: the wait ends.                            *)
(*                                                                         *)
(* Properties:                                                             *)
(*  - MasterElection's OneMasterPerEpochInv, MasterOwnsEpochInv,           *)
(*    NoStaleMastershipInv, EpochMonotoneProp, StaleCommandRejectedProp.   *)
(*  - OneTakeOverPerViewInv (PassOver's, a view now its id and its copy):  *)
(*    no two running Masters took over from one view but when one holds    *)
(*    the other failed. The succession answers the loss of a view's Master *)
(*    with one take-over; a pass-over makes two only from two views of one *)
(*    epoch (two copies of one id, or two ids). Passing over a member that *)
(*    prepared the same view (mutant DivergedSameView) lets that member,   *)
(*    an Observer ahead in the same succession, take over beside the node  *)
(*    that passed it.                                                      *)
(*  - DivergedLiveness: under fairness, once the liar has stopped lying    *)
(*    (it crashed; it may restart honest), eventually, for good, one       *)
(*    running Master leads every running node in its epoch (ElectionLiar's *)
(*    Agreed). Without the rule (mutant DivergedNone) it fails: seed       *)
(*    30979's story; with the rule for another digest under n's view's id  *)
(*    only (mutant DivergedSameIdOnly, the rule before) it fails where a   *)
(*    copy never arrives.                                                  *)
(*                                                                         *)
(* What TLC shows (MCDivergedView.tla has the models; one worker): PN1 the *)
(* liar and Master of epoch 1, which switches to (1, 1) with a copy per    *)
(* correct node out of Std, S1b (Std's Observers, another digest) and Safe *)
(* (safe mode from P3: PN2 a Worker), crashes and may restart.             *)
(*  - MCDivergedView (PN2 and PN3 the Observers, Safe's Observer PN3): 542 *)
(*    states, no violation. Without the rule (mutant DivergedNone) TLC     *)
(*    finds seed 30979 (438 states): PN1 switches PN3 into (1, 1) Std and  *)
(*    PN2 into (1, 1) Safe, crashes and restarts; PN3, behind PN2 in its   *)
(*    copy, declares PN1 and waits for ever for PN2, which it hears; PN2   *)
(*    runs as a Worker of its copy and never takes over; PN1 waits to be   *)
(*    commanded: no Master ever again. Passing over a member that prepared *)
(*    the same view (mutant DivergedSameView; 324 states): PN1 switches    *)
(*    both into (1, 1) Std and crashes; PN2, the first Observer, takes     *)
(*    over epoch 2, and PN3 passes PN2 over on its Prepared of that same   *)
(*    view and takes over epoch 3: two Masters from one view, neither      *)
(*    holding the other failed. WitnessDivergedPassOverInv: PN3, in (1, 1) *)
(*    S1b, passes over PN2, in (1, 1) Std, takes over epoch 3, and PN2     *)
(*    follows it; WitnessTwoTakeOversOneIdInv: PN2 takes over from Std and *)
(*    PN3 from S1b, both running (OneTakeOverPerViewInv allows it).        *)
(*  - MCDivergedViewLost (MCDivergedView's nodes and copies; the liar's    *)
(*    copies reach a non-empty set of correct nodes, MCLiarSwitchToLost):  *)
(*    830 states, no violation. With the rule before (mutant               *)
(*    DivergedSameIdOnly) TLC finds the copy that never arrives: PN1       *)
(*    switches PN2 alone into (1, 1) Safe, crashes and restarts; PN3, in   *)
(*    (1, 0), where PN2 is the first Observer, declares PN1 and waits for  *)
(*    ever for PN2, which it hears and whose Prepared names a newer id of  *)
(*    PN3's epoch; PN2 runs as a Worker of its copy and never takes over;  *)
(*    PN1 waits to be commanded. DivergedNone and DivergedSameView fail    *)
(*    there too (634 and 485 states). WitnessNewerSwitchPassOverInv: PN1   *)
(*    switches PN2 alone into (1, 1) Std and crashes; PN3, in (1, 0),      *)
(*    passes PN2 over on its Prepared of (1, 1), takes over epoch 3, and   *)
(*    PN2 follows it (in the runtime PN2, an Observer of its copy, takes   *)
(*    over first, during the wait).                                        *)
(*  - MCDivergedViewFour (bench; PN4 a Worker of Std, Safe's Observers PN3 *)
(*    and PN4): 8,014 states, no violation; both mutants fail there too    *)
(*    (4,878 and 3,541 states).                                            *)
(*  - By hand: with a false declaration no violation                       *)
(*    (MCDivergedView, MaxFalseSuspicions = 1: 4,574 states, 4,352 with    *)
(*    the rule before, since a node that declared the liar before its      *)
(*    switch passes over a member that took it; MCDivergedViewLost: 6,949  *)
(*    states), nor in MCDivergedViewFour with copies missing (13,954       *)
(*    states). With a crash of a correct node too                          *)
(*    (MCDivergedViewFour, MaxCrashes = 2) the safety properties hold      *)
(*    (301,253 states, DSpec), and DivergedLiveness fails for a reason     *)
(*    outside the rule: PN3 crashes before its copy arrives, PN2 and PN4   *)
(*    run as Workers of their copies, and no Observer is left (a liar      *)
(*    together with another fault).                                        *)
(*                                                                         *)
(* Abstracted from the runtime besides: a view's content is its copy's     *)
(* Observers (no configuration, tasks nor failed set: ValueFault's rules 3 *)
(* to 5 are that spec's, and the liar's copies here are valid and exclude  *)
(* no one); the Observers' order is the succession's (priority) order; a   *)
(* Prepared arrives once sent (its receipt, within a third of a period,    *)
(* precedes the end of the wait), and the rule reads the Prepared of x of  *)
(* n's current id (note_divergence resets with the view) and x's newest    *)
(* Prepared (ConfigSwitch keeps each node's newest Prepared of an id newer *)
(* than its view's); the liar is the Master, so a member's own lie (it can *)
(* have only itself passed over) is not modelled; evidence is n's own      *)
(* declaration (Exclusion.tla's two monitors and the lease are those       *)
(* specs'); PassOver's member behind (an epoch below the view's) is that   *)
(* spec's: no honest message is lost here, so a member behind always has a *)
(* Command on its way to it, and that rule would pass no one; honest       *)
(* Masters switch no more within an epoch (their views are (e, 1), Std: a  *)
(* take-over's, a reclaim's, a warm boot's) and neither hand over nor      *)
(* fence.                                                                  *)
(*                                                                         *)
(* Not covered (stated, not hidden): copies of two ids. If the liar sends  *)
(* (1, 1) Safe to PN2 and (1, 2) Std or S1b to PN3, where PN2 is the first *)
(* Observer, and crashes, PN2 goes by (1, 1), a Worker, and PN3 by (1, 2): *)
(* PN2's newest Prepared names an older switch of PN3's epoch, neither     *)
(* another digest under PN3's id nor a newer switch, and its heartbeats    *)
(* say PN3's epoch, so PN2 is neither diverged nor behind. PN3 waits for   *)
(* ever for PN2, PN2 (a Worker) for a Master, and PN1, restarted, to be    *)
(* commanded (by hand, the liar's switch (1, 1) to PN2 and (1, 2) to PN3,  *)
(* any copies: the safety properties hold, DivergedLiveness fails, 438     *)
(* states; 2,654 with each copy of either id, to some correct nodes or     *)
(* all). The runtime reads the same (diverged_members). The same order     *)
(* arises with an honest Master, which the spec does not model (its honest *)
(* Masters switch no more within an epoch): a switch that makes a member   *)
(* ahead an Observer, where its view before made it a Worker, reaches n    *)
(* but not that member (its Command lost), and the Master crashes. A rule  *)
(* that also passes over a member whose newest Prepared names an older     *)
(* switch of the receiver's epoch holds every property there (by hand: 622 *)
(* and 2,838 states, the two models above), but here a Prepared arrives    *)
(* once sent: in the runtime a member whose Prepared of n's view is lost   *)
(* looks behind, and, in n's view, may take over beside n from one view.   *)
(***************************************************************************)
EXTENDS ElectionLiar

CONSTANTS
    Copies,        \* the copies a view may be (digests); Std is an honest Master's
    Std,           \* the copy whose Observers are ObserversOf(epoch): every honest view
    CopyObservers  \* [Copies -> SUBSET Nodes]: the Observers a copy other than Std names

ASSUME CopyAssumption ==
    /\ Std \in Copies
    /\ CopyObservers \in [Copies -> SUBSET Nodes]

VARIABLES
    seq,            \* [Nodes -> Nat], the switch number of the node's view within its epoch
    copy,           \* [Nodes -> Copies], the copy of the view the node holds (its digest)
    prepared,       \* the correct nodes' Prepared acks: [from, epoch, seq, copy] each
    liarSwitch,     \* env: the liar's switch, a copy per correct node it reaches: [to,
                    \* epoch, seq, copy] each
    takenFrom,      \* history: [Nodes -> view], the view the node last took over from
                    \* (epoch 0: none; its mastership, if any, is a warm boot's)
    passedDiverged, \* history: a take-over passed over a member that prepared another view
    passedNewer     \* history: a take-over passed over a member whose Prepared names a
                    \* newer switch of the taker's view's epoch

dVars == <<seq, copy, prepared, liarSwitch, takenFrom, passedDiverged, passedNewer>>
divVars == <<allVars, dVars>>

ViewIds == [epoch : Nat, seq : Nat, copy : Copies]
NoView == [epoch |-> 0, seq |-> 0, copy |-> Std]

\* The Observers of a view of epoch e in copy c, and the role it gives a node that is not
\* its Master.
ObserversIn(c, e) == IF c = Std THEN ObserversOf(e) ELSE CopyObservers[c]
RoleInCopy(x, c, e) == IF x \in ObserversIn(c, e) THEN "Observer" ELSE "Worker"

\* The Observers n's copy places ahead of it in the succession (the nodes between the
\* view's Master and n in priority order that the copy names Observers).
AheadIn(n) == {x \in Ahead(n) : x \in ObserversIn(copy[n], epoch[n])}

\* The seq of an honest Command of epoch e: the initial view (1, 0), else a take-over's,
\* a reclaim's or a warm boot's first switch (e, 1).
SeqOf(e) == IF e = 1 THEN 0 ELSE 1

DTypeOK ==
    /\ LTypeOK
    /\ seq \in [Nodes -> Nat]
    /\ copy \in [Nodes -> Copies]
    /\ prepared \subseteq [from : Nodes, epoch : Nat, seq : Nat, copy : Copies]
    /\ liarSwitch \subseteq [to : Nodes, epoch : Nat, seq : Nat, copy : Copies]
    /\ takenFrom \in [Nodes -> ViewIds]
    /\ passedDiverged \in BOOLEAN
    /\ passedNewer \in BOOLEAN

\* ElectionLiar's initial state (the liar lies until it crashes): every node in the initial
\* view (1, 0), Std.
DInit ==
    /\ LInit
    /\ seq = [n \in Nodes |-> 0]
    /\ copy = [n \in Nodes |-> Std]
    /\ prepared = {}
    /\ liarSwitch = {}
    /\ takenFrom = [n \in Nodes |-> NoView]
    /\ passedDiverged = FALSE
    /\ passedNewer = FALSE

(***************************************************************************)
(* The liar's two views under one id                                       *)
(***************************************************************************)

\* The copies the liar may send: one per correct node (a definition, so that a model lets
\* it leave correct nodes out: MCDivergedViewLost's MCLiarSwitchToLost).
LiarSwitchTo == [Correct -> Copies]

\* The liar, the Master of its own epoch, switches to (epoch, seq + 1) and sends each
\* correct node cp names its own copy, once (a node cp leaves out never has one).
ForgeSwitch(cp) ==
    /\ lying
    /\ alive[Liar]
    /\ role[Liar] = "Master"
    /\ liarSwitch = {}
    /\ liarSwitch' = {[to |-> x, epoch |-> epoch[Liar], seq |-> seq[Liar] + 1,
                         copy |-> cp[x]] : x \in DOMAIN cp}
    /\ seq' = [seq EXCEPT ![Liar] = @ + 1]
    /\ UNCHANGED <<allVars, copy, prepared, takenFrom, passedDiverged, passedNewer>>

\* The id (e, s) is newer than n's view's.
NewerId(n, e, s) == e > epoch[n] \/ (e = epoch[n] /\ s > seq[n])

\* A correct node x adopts its copy of the liar's switch, newer than its view (the
\* runtime's Command from the view's Master): it takes the role the copy gives it and sends
\* its Prepared, which names its copy. It arrives after the liar's crash too, before any
\* node declares the liar (SwitchDelivered).
ReceiveSwitch(x, c) ==
    /\ c \in liarSwitch
    /\ c.to = x
    /\ alive[x]
    /\ Acts(x)
    /\ Owner(c.epoch) = Liar
    /\ NewerId(x, c.epoch, c.seq)
    /\ epoch' = [epoch EXCEPT ![x] = c.epoch]
    /\ seq' = [seq EXCEPT ![x] = c.seq]
    /\ copy' = [copy EXCEPT ![x] = c.copy]
    /\ leader' = [leader EXCEPT ![x] = Liar]
    /\ lastCommand' = [lastCommand EXCEPT ![x] = c.epoch]
    /\ role' = [role EXCEPT ![x] = RoleInCopy(x, c.copy, c.epoch)]
    /\ suspects' = IF c.epoch > epoch[x] THEN [suspects EXCEPT ![x] = @ \ {Liar}]
                                         ELSE suspects
    /\ prepared' = prepared \cup {[from |-> x, epoch |-> c.epoch, seq |-> c.seq,
                                   copy |-> c.copy]}
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED <<liarVars, liarSwitch, takenFrom, passedDiverged, passedNewer>>

\* Every copy of the liar's switch to a running node has arrived, or is no longer newer.
SwitchDelivered == \A c \in liarSwitch : alive[c.to] => ~NewerId(c.to, c.epoch, c.seq)

(***************************************************************************)
(* The pass-over                                                           *)
(***************************************************************************)

\* x prepared another view under the id of n's view (NodeProtocol::note_divergence): n's
\* view has seq >= 1, and x's Prepared of that id names a digest other than n's view's.
OtherCopy(n, x) ==
    /\ seq[n] >= 1
    /\ \E p \in prepared :
          /\ p.from = x
          /\ p.epoch = epoch[n] /\ p.seq = seq[n]
          /\ p.copy # copy[n]

\* p is the newest Prepared of its sender: none of its sender's names a newer id.
NewestPrepared(p) ==
    ~\E q \in prepared :
        /\ q.from = p.from
        /\ (q.epoch > p.epoch \/ (q.epoch = p.epoch /\ q.seq > p.seq))

\* x's newest Prepared names a switch of n's view's epoch newer than n's view, whatever its
\* digest, at any seq of n's view, 0 too (ConfigSwitch::prepared_newer_switch): x took a
\* Command of the epoch's Master, its one writer, that never reached n.
\* The Master of n's epoch still runs as that Master (alive, not restarted: a restart
\* makes it a Worker). The runtime's reading, from x's side: x's heartbeats acknowledge
\* that Master's, in the incarnation first heard, with a heartbeat newer each period
\* (NodeProtocol::hears_master); the spec has no deafness, so x hears it exactly when it
\* runs.
MasterRuns(e) == alive[Owner(e)] /\ role[Owner(e)] = "Master" /\ epoch[Owner(e)] = e

NewerSwitch(n, x) ==
    /\ \E p \in prepared :
          /\ p.from = x
          /\ NewestPrepared(p)
          /\ p.epoch = epoch[n] /\ p.seq > seq[n]
    /\ ~MasterRuns(epoch[n])

\* x goes by another view than n's (NodeProtocol::diverged_members): x is not the Master of
\* n's view, and it prepared another view under n's view's id or a newer switch of its
\* epoch.
Diverged(n, x) ==
    /\ x # Owner(epoch[n])
    /\ OtherCopy(n, x) \/ NewerSwitch(n, x)

\* The members ahead of an Observer n that it passes over by the rule PassBy(n, x).
PassedBy(PassBy(_, _), n) ==
    IF role[n] = "Observer" THEN {x \in AheadIn(n) \ suspects[n] : PassBy(n, x)} ELSE {}

Passed(n) == PassedBy(Diverged, n)

\* ElectionLiar's take-over (its guard the runtime's, its epoch the first n owns above
\* TakeOverFloor(n)) by an Observer (Election::may_take_over) with every Observer its copy
\* places ahead of it declared or passed over (Election::ahead_all_suspected(view,
\* passed)), by the rule PassBy, a parameter so that a mutant changes it. The new view is
\* (e, 1), Std; takenFrom records the view taken over from.
TakeOverBy(PassBy(_, _), n) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] = "Observer"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ DeclaredGone(n)
    /\ AheadIn(n) \subseteq suspects[n] \cup PassedBy(PassBy, n)
    /\ LET e == NextEpochAbove(n, TakeOverFloor(n)) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ passedDiverged' = (passedDiverged \/ PassedBy(PassBy, n) # {})
    /\ passedNewer' = (passedNewer \/ \E x \in PassedBy(PassBy, n) : NewerSwitch(n, x))
    /\ takenFrom' = [takenFrom EXCEPT ![n] = [epoch |-> epoch[n], seq |-> seq[n],
                                              copy |-> copy[n]]]
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED <<liarVars, prepared, liarSwitch>>

TakeOver(n) == TakeOverBy(Diverged, n)

(***************************************************************************)
(* ElectionLiar's other steps, with views                                  *)
(***************************************************************************)

\* A node declares a crashed node failed; the liar only once its switch's copies arrived.
DSuspect(n, m) == LSuspect(n, m) /\ (m = Liar => SwitchDelivered) /\ UNCHANGED dVars
DSuspectLeft(n, m) == SuspectLeft(n, m) /\ UNCHANGED dVars

\* A Master that moves past an epoch (Reclaim) or warm-boots opens (e, 1), Std.
DReclaim(n, above) ==
    /\ Reclaim(n, above)
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ UNCHANGED <<prepared, liarSwitch, takenFrom, passedDiverged, passedNewer>>
DWarmBoot(n) ==
    /\ LWarmBoot(n)
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ takenFrom' = [takenFrom EXCEPT ![n] = NoView]
    /\ UNCHANGED <<prepared, liarSwitch, passedDiverged, passedNewer>>

DBroadcastCommand(n) == LBroadcastCommand(n) /\ UNCHANGED dVars

\* ElectionLiar's receipt of an honest Command, not of an older seq of the node's epoch (a
\* node holding the liar's (1, 1) rejects (1, 0)); a newer epoch's view is (e, 1), Std,
\* and its receiver sends its Prepared.
DReceiveCommand(n, msg) ==
    /\ LReceiveCommand(n, msg)
    /\ msg.epoch = epoch[n] => SeqOf(msg.epoch) >= seq[n]
    /\ IF msg.epoch > epoch[n]
          THEN /\ seq' = [seq EXCEPT ![n] = SeqOf(msg.epoch)]
               /\ copy' = [copy EXCEPT ![n] = Std]
               /\ prepared' = prepared \cup {[from |-> n, epoch |-> msg.epoch,
                                              seq |-> SeqOf(msg.epoch), copy |-> Std]}
          ELSE UNCHANGED <<seq, copy, prepared>>
    /\ UNCHANGED <<liarSwitch, takenFrom, passedDiverged, passedNewer>>

\* The liar's crash ends its lies (LCrash); the last node down takes every message with it.
DCrash(n) ==
    /\ LCrash(n)
    /\ liarSwitch' = IF \A x \in Nodes \ {n} : ~alive[x] THEN {} ELSE liarSwitch
    /\ UNCHANGED <<seq, copy, prepared, takenFrom, passedDiverged, passedNewer>>

\* A restarted node waits to be commanded; the view it held says nothing until then.
DRestart(n) ==
    /\ LRestart(n)
    /\ seq' = [seq EXCEPT ![n] = 0]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ UNCHANGED <<prepared, liarSwitch, takenFrom, passedDiverged, passedNewer>>

(***************************************************************************)
(* Next state and fairness                                                 *)
(***************************************************************************)

\* Every step but the take-over, which DNext and a mutant's next-state relation add.
\* ElectionLiar's other lies (MaxLies), hand-overs and fences are not steps here.
DNextBut ==
    \/ \E cp \in LiarSwitchTo : ForgeSwitch(cp)
    \/ \E x \in Nodes, c \in liarSwitch : ReceiveSwitch(x, c)
    \/ \E n, m \in Nodes : DSuspect(n, m)
    \/ \E n, m \in Nodes : DSuspectLeft(n, m)
    \/ \E n \in Nodes, e \in {epoch[x] : x \in Nodes} : DReclaim(n, e)
    \/ \E n \in Nodes : DWarmBoot(n)
    \/ \E n \in Nodes : DBroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : DReceiveCommand(n, msg)
    \/ \E n \in Nodes : DCrash(n)
    \/ \E n \in Nodes : DRestart(n)

\* ElectionLiar's fairness (LFairness) but the take-over's, which DFairSpec and a mutant's
\* spec add; a copy of the liar's switch arrives. The liar need not lie.
DFairnessBut ==
    /\ \A n, m \in Nodes : WF_divVars(~alive[m] /\ DSuspect(n, m))
    /\ \A n, m \in Nodes : WF_divVars(DSuspectLeft(n, m))
    /\ \A n \in Nodes : WF_divVars(\E e \in {epoch[x] : x \in Nodes} : DReclaim(n, e))
    /\ WF_divVars(\E n \in Nodes : DWarmBoot(n))
    /\ \A n \in Nodes : WF_divVars(DBroadcastCommand(n))
    /\ \A n \in Nodes : WF_divVars(\E msg \in msgs : DReceiveCommand(n, msg))
    /\ \A x \in Nodes : WF_divVars(\E c \in liarSwitch : ReceiveSwitch(x, c))

DNext == DNextBut \/ \E n \in Nodes : TakeOver(n)
DSpec == DInit /\ [][DNext]_divVars
DFairSpec == DSpec /\ DFairnessBut /\ \A n \in Nodes : WF_divVars(TakeOver(n))

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No two running Masters took over from the same view (its id and its copy) but when one
\* holds the other failed: the first Observer of its succession that runs takes over, and
\* the others follow it.
OneTakeOverPerViewInv ==
    \A n, m \in Nodes :
        (/\ n # m
         /\ alive[n] /\ alive[m]
         /\ role[n] = "Master" /\ role[m] = "Master"
         /\ takenFrom[n].epoch # 0
         /\ takenFrom[n] = takenFrom[m])
        => n \in suspects[m] \/ m \in suspects[n]

\* Under fairness, once the liar stopped lying (it crashed), eventually, for good, one
\* running Master leads every running node in its epoch (ElectionLiar's Agreed).
DivergedLiveness == <>~lying => <>[]Agreed

=============================================================================
