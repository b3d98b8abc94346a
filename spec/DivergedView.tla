---------------------------- MODULE DivergedView ----------------------------
(***************************************************************************)
(* The pass-over of a member that goes by another view than the receiver's *)
(* own: one that prepared another view under the id of the receiver's, or  *)
(* a newer switch of its epoch, or that never prepared the receiver's view *)
(* (docs/fault-model.md, "A Master's two views under one id left a correct *)
(* Observer waiting for a Worker"; keel-sim --liar, prototype3 seed        *)
(* 30979). The module extends ElectionLiar for the succession, the         *)
(* runtime's take-over guard (DeclaredGone), rule (2) (SuspectLeft),       *)
(* Reclaim and the liar's crash and honest restart, and adds what the      *)
(* election alone does not have: a view's id (its epoch and switch number, *)
(* seq), its copy (the digest a Prepared names, and the Observers the copy *)
(* says), the correct nodes' Prepared, and the liar's one lie here, a      *)
(* switch whose copies differ or miss nodes (and, where a model lets it, a *)
(* second switch to the nodes the first missed).                           *)
(*                                                                         *)
(* The lie (ForgeSwitch). The liar, the Master of its own epoch e, makes a *)
(* switch (e, s+1), s >= 0 its view's seq, and sends each correct node a   *)
(* copy of its own (keel-sim's liar changes a Command's configuration per  *)
(* receiver), or, where a model lets it (LiarSwitchTo;                     *)
(* MCDivergedViewLost), some correct nodes only: a copy never sent, or     *)
(* lost for good when the liar crashes, leaves its node in the view it     *)
(* holds. Where a model lets it (LiarSwitchAgainTo; MCDivergedViewTwoIds), *)
(* the liar switches again, to (e, s+2), with a copy to each of some       *)
(* correct nodes its first switch left out (ForgeSwitchAgain): copies of   *)
(* two ids, which an honest Master makes too when its newer switch reaches *)
(* some nodes and not others (its Command lost) before it crashes. A copy  *)
(* is one of the constant Copies: Std, the view an honest Master of e      *)
(* sends (its Observers ObserversOf(e)), or another, whose Observers       *)
(* CopyObservers names, in the succession's order: a copy may make a node  *)
(* a Worker that another copy makes the first Observer (S1 and safe mode   *)
(* from P3 in seed 30979), or name the same Observers with another digest  *)
(* (a task placed elsewhere). A correct node adopts its copy when its id   *)
(* is newer than its view's (ReceiveSwitch; the runtime's Command), takes  *)
(* the role the copy gives it, and sends its Prepared, which names the     *)
(* view (NodeProtocol: Ack{Prepared, epoch, seq, view_digest}); DDS binds  *)
(* each Prepared to its sender. The copies sent arrive before any node     *)
(* declares the liar (delays of a third of a period, detection after       *)
(* MissLimit periods): a node declares the liar only once no copy to a     *)
(* running correct node is still newer than that node's view               *)
(* (SwitchDelivered).                                                      *)
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
(*    crashed too);                                                        *)
(*  - or x never prepared n's view: no Prepared of x names n's view (its   *)
(*    epoch, its seq and its digest), n's view having seq >= 2             *)
(*    (NeverPrepared; not at seq 1, where x may be in the epoch's first    *)
(*    view, seq 0: the initial view of a node that booted late, where it   *)
(*    may be an Observer that takes over in its own time, keel-sim         *)
(*    earth-observation seed 7050; that view and a hand-over's have no     *)
(*    Prepared from every member). x goes by an older switch of n's epoch  *)
(*    (copies of two ids: a newer switch that reached n and not x, the     *)
(*    liar's here, an honest Master's whose Command to x was lost in the   *)
(*    runtime too) or by another view. The runtime's reading: a member     *)
(*    that took n's view and waits with it repeats its Prepared every      *)
(*    period until the view activates, and one past its Prepared answers   *)
(*    n's repeated Prepared, so a member whose Prepared of n's view n      *)
(*    never got for 2 miss_limit periods never took it. If that guess is   *)
(*    wrong (its Prepared lost every period), the member, an Observer      *)
(*    ahead in the same view, takes over first during the wait: at most    *)
(*    two take-overs, in two epochs. Here a Prepared arrives once sent,    *)
(*    and the rule is exact. It overlaps the other two (a member that     *)
(*    never prepared n's view may have prepared a newer switch or another  *)
(*    copy) without covering them: a member that prepared n's view and    *)
(*    then a newer switch is NewerSwitch's alone; OtherCopy has no guard   *)
(*    on the Master, and NewerSwitch holds at seq 0 too.                   *)
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
(* newer view acknowledges it no more). The wait outlasts a delivery (a    *)
(* third of a period): n passes over a member for never preparing its view *)
(* only once every Command of n's epoch and every copy of the liar's       *)
(* switch on its way to that member has arrived (DeliveredTo). Without     *)
(* that, and with the rule at seq >= 1, TLC found two take-overs from one  *)
(* view (by hand): with a false declaration (MCDivergedView,               *)
(* MaxFalseSuspicions = 1) PN3, which declared PN1 before its switch,      *)
(* passed over PN2, whose copy of PN3's very view was still on its way;    *)
(* with a second crash (MCDivergedViewFour, MaxCrashes = 2) PN4, in        *)
(* (2, 1), passed over PN3, to which the Command of PN2, crashed, was      *)
(* still on its way; the member then took that view and took over too. At  *)
(* seq >= 2 the false-declaration checks find none without it (by hand:    *)
(* MCDivergedView and MCDivergedViewTwoIds, MaxFalseSuspicions = 1); it    *)
(* stays, as the wait's abstraction. A member passed over for a newer      *)
(* switch, or for                                                          *)
(* never preparing n's view, must besides no longer hear the Master of n's *)
(* epoch (its heartbeats' acknowledgements of that Master's stopped        *)
(* moving, or name a later incarnation: NodeProtocol::hears_master);       *)
(* modelled as MasterRuns, the spec having no deafness. The runtime needs  *)
(* it for its quorum, which a member passed over leaves (keel-sim          *)
(* prototype3 seed 12313: PN3, deaf to a live PN1, missed PN1's switch     *)
(* that PN2 took, passed PN2 over and took over alone); the spec has no    *)
(* quorum, so no property here fails without it, for either rule (by hand: *)
(* the three CI models, and with MaxFalseSuspicions = 1), and the          *)
(* runtime's unit test                                                     *)
(* AMemberThatTookANewerSwitchAndStillHearsTheMasterIsNotPassedOver is its *)
(* check. The spec has no time, and neither loss nor deafness here: once   *)
(* the guard holds the pass-over is enabled, and so is the member's own    *)
(* take-over when its copy allows it, in either order; both may happen,    *)
(* each opening an epoch its taker owns (two take-overs from two views of  *)
(* one epoch), and the Master of the older epoch adopts the newer one's    *)
(* Command. Liveness takes the pass-over as weakly fair as any take-over:  *)
(* the wait ends.                                                          *)
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
(*    only (mutant DivergedSameIdOnly) it fails where a copy never         *)
(*    arrives; without NeverPrepared (mutant DivergedNoNeverPrepared, the  *)
(*    rule before) it fails for copies of two ids.                         *)
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
(*    830 states, no violation (at seq >= 1, NeverPrepared would also let  *)
(*    PN3, in (1, 1), pass over PN2, left in (1, 0), where PN2 is an       *)
(*    Observer that may take over too: 910 states, two take-overs from two *)
(*    views of epoch 1; the runtime's seed 7050, where that sent the       *)
(*    cluster to safe mode). With the rule for another digest only (mutant *)
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
(*  - MCDivergedViewTwoIds (MCDivergedViewLost, and the liar may switch    *)
(*    again, to (1, 2), with a copy to each of a non-empty set of the      *)
(*    correct nodes its first switch left out, MCLiarSwitchAgainTo): 2,030 *)
(*    states, no violation. Without NeverPrepared (mutant                  *)
(*    DivergedNoNeverPrepared, the rule before; 1,846 states) TLC finds    *)
(*    the copies of two ids: PN1 switches PN2 alone into (1, 1) Safe, then *)
(*    PN3 alone into (1, 2) Std, crashes and restarts; PN3, where PN2 is   *)
(*    the first Observer, declares PN1 and waits for ever for PN2, which   *)
(*    it hears and whose newest Prepared names an older switch of PN3's    *)
(*    epoch; PN2 runs as a Worker of its copy and never takes over; PN1    *)
(*    waits to be commanded. That mutant holds in MCDivergedView and       *)
(*    MCDivergedViewLost (542 and 830 states): only two ids need the rule. *)
(*    WitnessNeverPreparedPassOverInv: PN1 switches PN2 alone into (1, 1)  *)
(*    Std, then PN3 alone into (1, 2) Std, and crashes; PN3 passes PN2     *)
(*    over by NeverPrepared alone, takes over epoch 3, and PN2 follows it  *)
(*    (in the runtime PN2, an Observer of its copy, takes over first,      *)
(*    during the wait).                                                    *)
(*  - MCDivergedViewFour (bench; PN4 a Worker of Std, Safe's Observers PN3 *)
(*    and PN4): 8,014 states, no violation; DivergedNone and               *)
(*    DivergedSameView fail there too (4,878 and 3,541 states).            *)
(*  - By hand: with a false declaration no violation (MaxFalseSuspicions = *)
(*    1: MCDivergedView 4,484 states, MCDivergedViewLost 6,829,            *)
(*    MCDivergedViewTwoIds 16,809), nor in MCDivergedViewFour with copies  *)
(*    missing (13,954 states) or of two ids (91,530 states). With a crash  *)
(*    of a correct node too (MCDivergedViewFour, MaxCrashes = 2) the       *)
(*    safety properties hold (301,253 states, DSpec), and DivergedLiveness *)
(*    fails for a reason outside the rule: PN3 crashes, PN2 and PN4 run as *)
(*    Workers of their copies, and no Observer is left (a liar together    *)
(*    with another fault).                                                 *)
(*                                                                         *)
(* Abstracted from the runtime besides: a view's content is its copy's     *)
(* Observers (no configuration, tasks nor failed set: ValueFault's rules 3 *)
(* to 5 are that spec's, and the liar's copies here are valid and exclude  *)
(* no one); the Observers' order is the succession's (priority) order; a   *)
(* Prepared arrives once sent (its receipt, within a third of a period,    *)
(* precedes the end of the wait), and the rule reads the Prepared of x of  *)
(* n's current id (note_divergence resets with the view), x's newest       *)
(* Prepared (ConfigSwitch keeps each node's newest Prepared of an id newer *)
(* than its view's) and x's Prepared of n's very view; the liar is the     *)
(* Master, so a member's own lie (it can have only itself passed over) is  *)
(* not modelled; evidence is n's own declaration (Exclusion.tla's two      *)
(* monitors and the lease are those specs'); PassOver's member behind (an  *)
(* epoch below the view's) is that spec's: no honest message is lost here, *)
(* so a member behind always has a Command on its way to it, and that rule *)
(* would pass no one (nor does NeverPrepared before it arrives); honest    *)
(* Masters switch no more within an epoch (their views are (e, 1), Std: a  *)
(* take-over's, a reclaim's, a warm boot's; the liar's two switches with   *)
(* copies Std are an honest Master's newer switch lost to some nodes) and  *)
(* neither hand over nor fence; the liar's second switch goes only to      *)
(* nodes its first left out (a node that took both would be passed over    *)
(* for the newer one, NewerSwitch, as one that took it alone is).          *)
(*                                                                         *)
(* Not covered (stated, not hidden): a Prepared lost. Here a Prepared      *)
(* arrives once sent, so a member that never prepared n's view never took  *)
(* it, and NeverPrepared is exact. In the runtime a member that took n's   *)
(* view but whose Prepared of it was lost in every period of the wait (2   *)
(* miss_limit periods, its Prepared repeated each period) is passed over   *)
(* all the same. It is an Observer ahead of n in that very view, so it     *)
(* takes over first, during the wait, and its Command ends n's wait; only  *)
(* if that Command is lost too do both take over from one view, each in an *)
(* epoch of its own (two running Masters from one view, which              *)
(* OneTakeOverPerViewInv forbids and which is unreachable here), and the   *)
(* Master of the older epoch adopts the newer one's Command: at most two   *)
(* take-overs, in two epochs. Copies of two ids are covered: the liar's    *)
(* (1, 1) Safe to PN2 and (1, 2) to PN3, where PN2 is the first Observer,  *)
(* then its crash, is MCDivergedViewTwoIds's story, and an honest Master's *)
(* switch that reaches n and not the member ahead, then its crash, is that *)
(* story too (each id there has one copy, as an honest Master's has).      *)
(* Beyond the rule: a liar together with another fault (MaxCrashes = 2     *)
(* above).                                                                 *)
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
    passedNewer,    \* history: a take-over passed over a member whose Prepared names a
                    \* newer switch of the taker's view's epoch
    passedNever     \* history: a take-over passed over a member that never prepared the
                    \* taker's view (neither another copy nor a newer switch held for it)
                    \* and prepared an older switch of its epoch: copies of two ids

dVars == <<seq, copy, prepared, liarSwitch, takenFrom, passedDiverged, passedNewer,
          passedNever>>
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
    /\ passedNever \in BOOLEAN

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
    /\ passedNever = FALSE

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
    /\ UNCHANGED <<allVars, copy, prepared, takenFrom, passedDiverged, passedNewer,
                   passedNever>>

\* The copies the liar may send with a second switch, each to a correct node its first
\* switch left out: none (a definition, so that a model lets it switch again:
\* MCDivergedViewTwoIds's MCLiarSwitchAgainTo).
LiarSwitchAgainTo == {}

\* The liar, having switched once, switches again, to (epoch, seq + 1), and sends each
\* correct node cp names, one its first switch left out, its own copy, once: copies of two
\* ids, a newer switch that reached some nodes and not others.
ForgeSwitchAgain(cp) ==
    /\ lying
    /\ alive[Liar]
    /\ role[Liar] = "Master"
    /\ liarSwitch # {}
    /\ \A c \in liarSwitch : c.seq = seq[Liar]
    /\ DOMAIN cp \cap {c.to : c \in liarSwitch} = {}
    /\ liarSwitch' = liarSwitch \cup
                      {[to |-> x, epoch |-> epoch[Liar], seq |-> seq[Liar] + 1,
                        copy |-> cp[x]] : x \in DOMAIN cp}
    /\ seq' = [seq EXCEPT ![Liar] = @ + 1]
    /\ UNCHANGED <<allVars, copy, prepared, takenFrom, passedDiverged, passedNewer,
                   passedNever>>

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
    /\ UNCHANGED <<liarVars, liarSwitch, takenFrom, passedDiverged, passedNewer,
                   passedNever>>

\* Every copy of the liar's switch to a running node x has arrived, or is no longer newer.
SwitchDeliveredTo(x) ==
    \A c \in liarSwitch : (c.to = x /\ alive[x]) => ~NewerId(x, c.epoch, c.seq)
SwitchDelivered == \A x \in Nodes : SwitchDeliveredTo(x)

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

\* Every Command of epoch e and every copy of the liar's switch on its way to x that x
\* would take has arrived: the wait (2 miss_limit periods) outlasts a delivery (a third
\* of a period).
DeliveredTo(x, e) ==
    /\ SwitchDeliveredTo(x)
    /\ ~\E msg \in msgs : msg.epoch = e /\ msg.epoch > epoch[x] /\ alive[x] /\ Acts(x)

\* x never prepared n's view (NodeProtocol::never_prepared): n's view has seq >= 2 (at seq
\* 1, x may be in the epoch's first view, seq 0, which has no Prepared from every member
\* and where x may be an Observer that takes over in its own time), no Prepared
\* of x names n's view (its epoch, its seq and its digest), and the Master of n's epoch no
\* longer runs (NewerSwitch's guard), once what was on its way to x has arrived
\* (DeliveredTo). A Prepared arrives here once sent, so x never took n's view; in the
\* runtime, one whose Prepared of n's view n did not receive for 2 miss_limit periods.
NeverPrepared(n, x) ==
    /\ seq[n] >= 2
    /\ ~\E p \in prepared :
          /\ p.from = x
          /\ p.epoch = epoch[n] /\ p.seq = seq[n] /\ p.copy = copy[n]
    /\ ~MasterRuns(epoch[n])
    /\ DeliveredTo(x, epoch[n])

\* x goes by another view than n's (NodeProtocol::diverged_members): x is not the Master of
\* n's view, and it prepared another view under n's view's id or a newer switch of its
\* epoch, or never prepared n's view.
Diverged(n, x) ==
    /\ x # Owner(epoch[n])
    /\ OtherCopy(n, x) \/ NewerSwitch(n, x) \/ NeverPrepared(n, x)

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
    /\ passedNever' = (passedNever \/ \E x \in PassedBy(PassBy, n) :
                         /\ NeverPrepared(n, x) /\ ~OtherCopy(n, x) /\ ~NewerSwitch(n, x)
                         /\ \E p \in prepared : /\ p.from = x /\ p.epoch = epoch[n]
                                               /\ 1 <= p.seq /\ p.seq < seq[n])
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
    /\ UNCHANGED <<prepared, liarSwitch, takenFrom, passedDiverged, passedNewer,
                   passedNever>>
DWarmBoot(n) ==
    /\ LWarmBoot(n)
    /\ seq' = [seq EXCEPT ![n] = 1]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ takenFrom' = [takenFrom EXCEPT ![n] = NoView]
    /\ UNCHANGED <<prepared, liarSwitch, passedDiverged, passedNewer, passedNever>>

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
    /\ UNCHANGED <<liarSwitch, takenFrom, passedDiverged, passedNewer, passedNever>>

\* The liar's crash ends its lies (LCrash); the last node down takes every message with it.
DCrash(n) ==
    /\ LCrash(n)
    /\ liarSwitch' = IF \A x \in Nodes \ {n} : ~alive[x] THEN {} ELSE liarSwitch
    /\ UNCHANGED <<seq, copy, prepared, takenFrom, passedDiverged, passedNewer,
                   passedNever>>

\* A restarted node waits to be commanded; the view it held says nothing until then.
DRestart(n) ==
    /\ LRestart(n)
    /\ seq' = [seq EXCEPT ![n] = 0]
    /\ copy' = [copy EXCEPT ![n] = Std]
    /\ UNCHANGED <<prepared, liarSwitch, takenFrom, passedDiverged, passedNewer,
                   passedNever>>

(***************************************************************************)
(* Next state and fairness                                                 *)
(***************************************************************************)

\* Every step but the take-over, which DNext and a mutant's next-state relation add.
\* ElectionLiar's other lies (MaxLies), hand-overs and fences are not steps here.
DNextBut ==
    \/ \E cp \in LiarSwitchTo : ForgeSwitch(cp)
    \/ \E cp \in LiarSwitchAgainTo : ForgeSwitchAgain(cp)
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
