---------------------------- MODULE ElectionLiar ----------------------------
(***************************************************************************)
(* Fault model 3 in the election (docs/fault-model.md, "Fault model 3"):   *)
(* one value-faulty processing node, Liar, against MasterElection's        *)
(* succession, and two receiver rules that keep its lies from fencing a    *)
(* correct node in another node's name or leaving the cluster without a    *)
(* Master for good (docs/fault-model.md, "A value-faulty node in the       *)
(* simulator": prototype3 seed 119042, earth-observation seed 13921). The  *)
(* module extends MasterElection: its nodes, epochs and their owners,      *)
(* commands, crashes and restarts, its honest steps and budgets            *)
(* (MaxHandOvers and MaxFences stay 0 in the models: no honest hand-over,  *)
(* but by hand, and no fence here).                                        *)
(*                                                                         *)
(* The liar, under its own identity as in ValueFault. While it runs its    *)
(* first boot it forges at most MaxLies messages, each a Command sent to   *)
(* one node alone (forged): a Command of an epoch of its own               *)
(* (ForgeCommand: seed 13921's readmission of PN1 into the liar's epoch    *)
(* 14, sent to PN1 only), or, as the Master of the receiver's view, a      *)
(* hand-over: a view of epoch e, seq 0, naming e's owner r its Master,     *)
(* which may exclude the receiver (ForgeHandOver; keel-sim's liar,         *)
(* nodes/sim/src/liar.cpp, changes a Command's master and failed set so).  *)
(* It may name any node: one that follows an epoch above e, as in seed     *)
(* 13921, or one that never takes e. While it lies it takes no step of the *)
(* protocol (Acts): what it sends then is forged, and its heartbeats say   *)
(* the epoch it held. Its crash ends the lies (a message of its in flight  *)
(* arrives before any node declares it, delays being a third of a period   *)
(* and detection MissLimit periods, or never), and it restarts as any node *)
(* does, honest from then on.                                              *)
(*                                                                         *)
(* A receiver takes a message of the liar's that passes its checks         *)
(* (ReceiveForged: NodeProtocol::handle_command, command_problem, then     *)
(* Election::receive_command): not stale and at most a lap of the          *)
(* succession above its epoch (InBound; adoptable_epoch), naming the owner *)
(* of its epoch, and for a hand-over sent by the Master of its view, to a  *)
(* node other than the one it names (Authorized). It adopts the epoch and  *)
(* obeys the view's master, as an Observer or Worker of the epoch, or as a *)
(* Worker that knows itself fenced when the view excludes it: such a view  *)
(* only stops what its receiver runs and is followed unchecked             *)
(* (ValueFault's rule 5).                                                  *)
(*                                                                         *)
(* Rule (1), a hand-over never excludes its receiver (KeepsReceiver:       *)
(* NodeProtocol::handle_command, counted unauthorized; unit test           *)
(* AHandOverNeverExcludesItsReceiver): an honest Master hands its view     *)
(* over only to the nodes that view keeps. Taken, a hand-over that         *)
(* excludes its receiver x fences x in r's name, though r excluded no one: *)
(* in seed 119042 PN3, fenced so, then refused PN1's real Commands as      *)
(* proof (under an edge rule that since binds no handed view, seed 15049;  *)
(* today the named Master, hearing x say it is excluded, would exclude it  *)
(* on that word). NoFenceInAnotherNameInv: no correct node is fenced by a  *)
(* hand-over (history fencedByHandOver).                                   *)
(*                                                                         *)
(* Rule (2), a Master that left its view (SuspectLeft:                     *)
(* NodeProtocol::note_master_left and declare_master_left,                 *)
(* HeartbeatMonitor::declare_left, a heartbeat.DeclareFailed line with     *)
(* reason "left" counted masters_left, then Election::suspect). A node's   *)
(* heartbeats say the highest epoch it adopted. An Observer n whose view's *)
(* Master m runs, neither waits nor is fenced (its heartbeats would say    *)
(* so: other declarations) and follows an epoch other than n's, while no   *)
(* Command of an epoch above n's is on its way to n, declares m failed on  *)
(* m's own word (Left). An epoch above n's: an honest node that adopts a   *)
(* newer epoch steps down from the older one for good. An epoch below: m   *)
(* never took the view n follows (a hand-over of the liar's naming m,      *)
(* which never reaches m, or a Command of an epoch of the liar's own,      *)
(* which it never opens).                                                  *)
(*                                                                         *)
(* An honest hand-over is the one way a node follows a Master in an epoch  *)
(* that Master has not yet taken: the Master that hands over adopts the    *)
(* new epoch at once, as the new Master's Observer or Worker (HandOver),   *)
(* and the runtime's other nodes of the view adopt its first copy (which   *)
(* the spec leaves out). The new Master takes it within a period or two,   *)
(* since a hand-over is repeated until its receiver commands, so n also    *)
(* waits while a hand-over m could still take (for m's boot, fresh for m)  *)
(* is on its way to m (NoHandOverTo). The runtime waits for 3 miss_limit   *)
(* periods with its view unchanged: longer than a Command takes to arrive  *)
(* (a Master repeats its Commands), than an honest new Master needs to     *)
(* take its hand-over, and than it waits for its voters. The spec has no   *)
(* time: n declares only when msgs holds no Command above its epoch and    *)
(* handOvers no hand-over m could take. Without the first guard take-overs *)
(* chase one another and the state space has no end; without the second    *)
(* the Master that hands over declares its receiver at once (3 states).    *)
(* The take-over that follows opens the first epoch n owns above the one m *)
(* follows when m is ahead, above n's own when m is behind (TakeOverFloor; *)
(* NodeProtocol::take_over's left_epoch_); m adopts it.                    *)
(*                                                                         *)
(* The rule before read only an epoch above the view's (mutant             *)
(* ElectionLeftAheadOnly): a hand-over of the liar's naming a node that    *)
(* never takes it left no Master for good, and the CI liveness model let   *)
(* the liar name only a node ahead.                                        *)
(*                                                                         *)
(* The take-over (LBecomeMaster: NodeProtocol::take_over,                  *)
(* Election::become_master) is guarded as the runtime guards it, so that   *)
(* rule (2) is what lets it happen: the Master of n's epoch is gone for n  *)
(* only once n declared it failed (its silence, its word that it is        *)
(* fenced, or that it left), or once it restarted since that epoch was     *)
(* opened, which its new boot says for good (DeclaredGone;                 *)
(* Election::ahead_all_suspected, HeartbeatMonitor's permanent declaration *)
(* of a restart). MasterElection's MasterGone takes a Master whose role or *)
(* epoch changed as gone by reading its state: the runtime's heartbeats    *)
(* carry no role (core/fsm/messages.hpp), and it had no counterpart of the *)
(* epoch clause before rule (2); in MasterElection that clause is rule (2) *)
(* already, for every node and at once, which is why seed 13921 needs this *)
(* module to show. And a Master that hears a node follow an epoch above    *)
(* its own whose owner it declared and is down, or restarted since, or     *)
(* which is its own and it never opened (seed 25282), claims the first     *)
(* epoch it owns above it (Reclaim: NodeProtocol::tick's newer_epoch_,     *)
(* Election::reclaim; trace election.BecomeMaster with `above`,            *)
(* TraceElection's Reclaim). Without it, a node the liar moved a lap up    *)
(* waits for ever for the succession of the liar's epoch while the others  *)
(* take over below it (MCElectionLiarLeft without Reclaim fails            *)
(* AgreementLiveness; 3,347 states). The runtime's take-over also opens    *)
(* above an epoch a voter acknowledges whose owner it replaces (seed       *)
(* 49016): here Reclaim reaches those epochs a step later; with the lease  *)
(* the step is too late (TakeOverEpoch.tla specifies the rule).            *)
(*                                                                         *)
(* Properties (the correct nodes are Nodes \ {Liar}):                      *)
(*  - MasterElection's OneMasterPerEpochInv, MasterOwnsEpochInv,           *)
(*    NoStaleMastershipInv, EpochMonotoneProp, StaleCommandRejectedProp.   *)
(*  - NoFenceInAnotherNameInv (rule 1).                                    *)
(*  - AgreementLiveness (rule 2): under fairness, once the liar has        *)
(*    stopped lying (it crashed) and every node runs for good, eventually, *)
(*    for good, one running Master is the Master of every node's view, in  *)
(*    its epoch (Agreed; the liar, restarted honest, counts as any node,   *)
(*    and may be that Master).                                             *)
(*                                                                         *)
(* What TLC shows (MCElectionLiar.tla has the models; one worker):         *)
(*  - MCElectionLiarHandOver (PN1, the first Master, lies at most three   *)
(*    times, naming any node; safety only): 27,551 states. Without rule    *)
(*    (1) (ElectionHandOverExcludesReceiver) PN1 hands PN3 a view of PN2's *)
(*    epoch 2 that excludes PN3, and PN3 follows it: fenced in PN2's name  *)
(*    (3 states). WitnessHandOverRefusedInv: such a hand-over is in flight *)
(*    and passes every other check. By hand: two lies and a false          *)
(*    declaration, 27,804 states; no violation.                            *)
(*  - MCElectionLiarLeft (PN1 lies at most twice, naming any node): 3,645  *)
(*    states. Without rule (2) (ElectionNoMasterLeft, its liar naming only *)
(*    a node ahead) TLC finds seed 13921 on three nodes (661 states): PN1  *)
(*    sends PN3 alone its epoch 4, hands PN2 epoch 3 naming PN3, crashes   *)
(*    and restarts. PN3 never takes an epoch below its own, and waits for  *)
(*    PN2, the owner of epoch 5, ahead of it in the succession; PN2 waits  *)
(*    for PN3, which it hears; PN1 waits to be commanded: no Master ever   *)
(*    again. With the old rule, a Master ahead of the view only            *)
(*    (ElectionLeftAheadOnly), a single lie does it (1,755 states): PN1    *)
(*    hands PN2 epoch 3 naming PN3, which stays in epoch 1, then crashes   *)
(*    and restarts; PN2 waits for PN3, whose heartbeats say an epoch below *)
(*    its view's; PN3 waits for PN2, the first Observer of epoch 1, which  *)
(*    it hears; PN1 waits. A rule with the other half only (a Master       *)
(*    behind the view) fails on seed 13921 (by hand, 3,438 states).        *)
(*    WitnessLeftTakeOverInv: PN3, handed PN2's epoch 2 while PN2 follows  *)
(*    PN1's epoch 4, declares PN2 left, takes over epoch 6, and every      *)
(*    running node follows it. WitnessBehindMasterLeftInv: PN3, handed     *)
(*    PN2's epoch 2 while PN2 stays in epoch 1, declares PN2 left, takes   *)
(*    over epoch 3, PN2 follows it, and so does PN1, crashed and restarted *)
(*    (unreachable with the old rule: 1,755 states).                       *)
(*  - By hand, no violation with three lies (27,551 states), with a false  *)
(*    declaration too (27,804), with PN2 or PN3 as the liar (1,250 and     *)
(*    2,216 states), nor when the take-over opens NextEpoch(n) instead of  *)
(*    an epoch above the one a Master that left for a newer one follows    *)
(*    (3,422 states): here Reclaim then moves past that epoch a step       *)
(*    later, so that part of rule (2) saves a take-over and binds no       *)
(*    property. With honest hand-overs beside the liar (MaxHandOvers = 1), *)
(*    79,387 states, and 105,384 without NoHandOverTo, no violation        *)
(*    either: that guard spares a Master that was handed its view a        *)
(*    declaration it does not deserve, and binds no property here.         *)
(*                                                                         *)
(* Not covered (stated, not hidden): lies in heartbeats (an epoch the liar *)
(* does not hold makes an Observer of its view declare it left and take    *)
(* over, which costs a take-over; the runtime bounds such an epoch by the  *)
(* adoptable bound), a lying Storage or interface node (seed 13921's IF1   *)
(* is left out: followers take no part in the election), honest fences     *)
(* beside the liar (honest hand-overs only by hand, above), the liar's own *)
(* protocol steps while it lies, and boots (a forged hand-over never       *)
(* reaches the node it names, so the boot check has nothing to refuse).    *)
(* The adoptable bound holds for the messages the liar sends, one lap per  *)
(* message as in ValueFault; SuspectLeft and Reclaim read any epoch above, *)
(* since the runtime's bound grows a lap per period and an epoch a node    *)
(* stays at is within it in the end. The views' checks of ValueFault       *)
(* (rules 3 to 5: the graph, peers' Prepared, backed exclusions) are that  *)
(* spec's: here a view is its epoch, its master and whether it excludes    *)
(* its receiver.                                                           *)
(***************************************************************************)
EXTENDS MasterElection

CONSTANTS
    Liar,     \* the value-faulty processing node; every other node is correct
    MaxLies   \* environment: at most this many messages the liar forges in a behaviour

ASSUME LiarAssumption == Liar \in Nodes /\ MaxLies \in Nat

VARIABLES
    forged,           \* env: the liar's messages, [to, epoch, master, excl] each
    lying,            \* the liar still lies: until it crashes (it restarts honest)
    fencedByHandOver, \* history: [Nodes -> BOOLEAN], the node took a hand-over excluding it
    leftTakeOver,     \* history: a node took over above the epoch of a Master it declared
                      \* left, ahead of its view
    behindTakeOver    \* history: a node took over from a correct Master it declared left,
                      \* behind its view

liarVars == <<forged, lying, fencedByHandOver, leftTakeOver, behindTakeOver>>
allVars == <<vars, liarVars>>

Correct == Nodes \ {Liar}

\* A message of the liar's: a Command of view (epoch, master), sent to `to` alone. Its
\* master is the liar (a Command of an epoch of its own) or another node, the owner of the
\* epoch (a hand-over: the view the liar hands over to that node, seq 0), and its view may
\* exclude its receiver (excl).
ForgedMessages == [to : Nodes, epoch : Nat, master : Nodes, excl : BOOLEAN]

IsHandOver(c) == c.master # Liar

LTypeOK ==
    /\ TypeOK
    /\ forged \subseteq ForgedMessages
    /\ lying \in BOOLEAN
    /\ fencedByHandOver \in [Nodes -> BOOLEAN]
    /\ leftTakeOver \in BOOLEAN
    /\ behindTakeOver \in BOOLEAN

LInit ==
    /\ Init
    /\ forged = {}
    /\ lying = TRUE
    /\ fencedByHandOver = [n \in Nodes |-> FALSE]
    /\ leftTakeOver = FALSE
    /\ behindTakeOver = FALSE

(***************************************************************************)
(* Receiver rules                                                          *)
(***************************************************************************)

\* The epoch bound (NodeProtocol::adoptable_epoch; ValueFault's MayCommand): not stale
\* (Fresh) and at most a lap of the succession above the receiver's epoch.
InBound(x, c) == c.epoch >= epoch[x] /\ c.epoch <= epoch[x] + N

\* Authority by role (NodeProtocol::handle_command): a Command's view names the owner of its
\* epoch; one whose master is not its sender is a hand-over, which only the Master of the
\* receiver's view sends (leader[x]), to a node other than the one it names.
Authorized(x, c) ==
    /\ Owner(c.epoch) = c.master
    /\ IsHandOver(c) => leader[x] = Liar /\ x # c.master

\* Rule (1): a hand-over never excludes its receiver (NodeProtocol::handle_command,
\* `AHandOverNeverExcludesItsReceiver`): the Master that hands its view over sends it only
\* to the nodes it keeps.
KeepsReceiver(x, c) == IsHandOver(c) => ~c.excl

(***************************************************************************)
(* The liar                                                                *)
(***************************************************************************)

\* The liar forges while it runs its first boot, within its budget.
MayForge == lying /\ alive[Liar] /\ Cardinality(forged) < MaxLies

\* The liar sends node x alone a Command of an epoch of its own, within a lap above x's
\* (seed 13921: PN2 readmitted PN1 into its epoch 14 with a Command sent to PN1 only).
ForgeCommand(x, e) ==
    /\ MayForge
    /\ x # Liar
    /\ Owner(e) = Liar
    /\ e >= epoch[x] /\ e <= epoch[x] + N
    /\ forged' = forged \cup {[to |-> x, epoch |-> e, master |-> Liar, excl |-> FALSE]}
    /\ UNCHANGED <<vars, lying, fencedByHandOver, leftTakeOver, behindTakeOver>>

\* The liar, Master of x's view, sends x alone a hand-over of epoch e, within a lap above
\* x's, to r, its owner, naming r Master; the view may exclude x (seed 119042). r is any
\* other node: one that follows a newer epoch (seed 13921: PN2 handed epoch 9 to PN3, PN4
\* and IF1 naming PN1, which followed PN2's epoch 14), or one that never takes e.
ForgeHandOver(x, r, e, excl) ==
    /\ MayForge
    /\ x # Liar /\ r # Liar /\ r # x
    /\ leader[x] = Liar
    /\ Owner(e) = r
    /\ e >= epoch[x] /\ e <= epoch[x] + N
    /\ forged' = forged \cup {[to |-> x, epoch |-> e, master |-> r, excl |-> excl]}
    /\ UNCHANGED <<vars, lying, fencedByHandOver, leftTakeOver, behindTakeOver>>

\* Node x takes a message of the liar's that passes its checks (NodeProtocol::
\* handle_command, then Election::receive_command): it adopts the view's epoch and obeys its
\* master, as an Observer or Worker of that epoch, or, when the view excludes it, as a
\* Worker that knows itself fenced (a view that excludes its receiver is followed
\* unchecked, ValueFault's rule 5). A Command of a newer epoch is a sign of life of its
\* sender, the liar. The liar's messages arrive while it runs: one in flight when it
\* crashes arrives before any node declares it (delays of a third of a period, detection
\* after MissLimit periods), or never. Keeps(_, _) is rule (1), a parameter so that a
\* mutant removes it.
ReceiveForgedBy(Keeps(_, _), x, c) ==
    /\ alive[x]
    /\ lying
    /\ c \in forged
    /\ c.to = x
    /\ InBound(x, c)
    /\ Authorized(x, c)
    /\ Keeps(x, c)
    /\ epoch' = [epoch EXCEPT ![x] = c.epoch]
    /\ leader' = [leader EXCEPT ![x] = c.master]
    /\ lastCommand' = [lastCommand EXCEPT ![x] = c.epoch]
    /\ role' = [role EXCEPT ![x] = IF c.excl \/ fenced[x] THEN "Worker"
                                    ELSE IF c.epoch > epoch[x] THEN RoleIn(x, c.epoch)
                                    ELSE @]
    /\ suspects' = IF c.epoch > epoch[x] THEN [suspects EXCEPT ![x] = @ \ {Liar}]
                                         ELSE suspects
    /\ fenced' = IF c.excl THEN [fenced EXCEPT ![x] = TRUE] ELSE fenced
    /\ fencedByHandOver' = IF c.excl /\ IsHandOver(c)
                              THEN [fencedByHandOver EXCEPT ![x] = TRUE]
                              ELSE fencedByHandOver
    /\ UNCHANGED <<alive, msgs, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenceCount, forged, lying, leftTakeOver,
                   behindTakeOver>>

ReceiveForged(x, c) == ReceiveForgedBy(KeepsReceiver, x, c)

(***************************************************************************)
(* Protocol: rule (2), the runtime's take-over, and the reclaim            *)
(***************************************************************************)

\* The liar takes no step of the protocol while it lies: what it sends then is forged.
Acts(n) == n # Liar \/ ~lying

\* m, the Master of n's view, says in its heartbeats that it follows an epoch other than
\* n's (a heartbeat says the highest epoch its sender adopted): a newer one, or an older
\* one, the view's epoch never taken; and neither that it waits nor that it is fenced
\* (which are other declarations).
Left(n, m) == alive[m] /\ ~Waiting(m) /\ ~fenced[m] /\ epoch[m] # epoch[n]

\* No hand-over m could still take is on its way to it: one for m's boot, fresh for m. An
\* honest hand-over is repeated until its receiver commands, and taken within a period or
\* two; until then the Master that handed over (in the runtime, the view's other nodes too)
\* follows m in an epoch m has not taken.
NoHandOverTo(m) == \A h \in handOvers : h.to = m => ~(MeantForThisBoot(m, h) /\ Fresh(m, h))

\* Rule (2) (NodeProtocol::note_master_left, declare_master_left; HeartbeatMonitor::
\* declare_left: heartbeat.DeclareFailed with reason "left", counted masters_left; then
\* Election::suspect): an Observer whose view's Master left it (LeftBy, a parameter so that
\* a mutant narrows it), while no Command of an epoch above its own is on its way to it nor
\* a hand-over to that Master, declares that Master failed on its own word. An honest node
\* that adopts a newer epoch steps down from the older one for good; one that is handed an
\* epoch takes it, or never will.
SuspectLeftBy(LeftBy(_, _), n, m) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] = "Observer"
    /\ m = Owner(epoch[n])
    /\ m # n
    /\ m \notin suspects[n]
    /\ LeftBy(n, m)
    /\ \A msg \in msgs : msg.epoch <= epoch[n]
    /\ NoHandOverTo(m)
    /\ suspects' = [suspects EXCEPT ![n] = @ \cup {m}]
    /\ UNCHANGED <<alive, role, epoch, leader, lastCommand, msgs, handOvers, boot,
                   restartEpoch, crashes, restarts, falseSuspicions, handOverCount, fenced,
                   fenceCount>>
    /\ UNCHANGED liarVars

SuspectLeft(n, m) == SuspectLeftBy(Left, n, m)

\* The Master of n's epoch is gone for n: n declared it failed (its silence, its word that
\* it is fenced, or that it left), or it restarted since that epoch was opened (its new
\* boot, heard in its heartbeats: its own word, for good). Election::ahead_all_suspected.
DeclaredGone(n) ==
    \/ epoch[n] = 0
    \/ LET m == Owner(epoch[n]) IN
          \/ m = n
          \/ m \in suspects[n]
          \/ restartEpoch[m] >= epoch[n]

\* n declared the Master of its epoch, which follows another epoch (rule (2)).
DeclaredLeft(n) ==
    LET m == Owner(epoch[n]) IN m # n /\ m \in suspects[n] /\ Left(n, m)

\* The epoch above which n takes over: the one the Master of its epoch follows, when n
\* declared it and it left for a newer one (NodeProtocol::take_over, left_epoch_); else
\* n's own, also when that Master follows an older one.
TakeOverFloor(n) ==
    IF DeclaredLeft(n) /\ epoch[Owner(epoch[n])] > epoch[n] THEN epoch[Owner(epoch[n])]
                                                             ELSE epoch[n]

\* MasterElection's BecomeMaster with the runtime's guard (DeclaredGone) and epoch: the
\* first one n owns above TakeOverFloor(n), which a Master that left then adopts.
LBecomeMaster(n) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] # "Master"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ DeclaredGone(n)
    /\ Ahead(n) \subseteq suspects[n]
    /\ LET e == NextEpochAbove(n, TakeOverFloor(n)) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ leftTakeOver' = (leftTakeOver \/ TakeOverFloor(n) # epoch[n])
    /\ behindTakeOver' = (behindTakeOver \/
                            (DeclaredLeft(n) /\ epoch[Owner(epoch[n])] < epoch[n]
                                             /\ Owner(epoch[n]) \in Correct))
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED <<forged, lying, fencedByHandOver>>

\* A Master that hears a node follow an epoch above its own whose owner it declared and is
\* down, or restarted since, or that is its own and it never opened, claims the first epoch
\* it owns above it and commands (NodeProtocol::tick's newer_epoch_, Election::reclaim;
\* trace election.BecomeMaster with `above`, TraceElection's Reclaim).
Reclaim(n, above) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] = "Master"
    /\ above > epoch[n]
    /\ \E x \in Nodes : alive[x] /\ epoch[x] = above
    /\ LET o == Owner(above) IN
          \/ o = n
          \/ o \in suspects[n] /\ ~alive[o]
          \/ restartEpoch[o] >= above
    /\ LET e == NextEpochAbove(n, above) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, role, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED liarVars

\* MasterElection's other steps, by a node that does not lie, leaving the liar's
\* variables alone.
LSuspect(n, m) == Acts(n) /\ Suspect(n, m) /\ UNCHANGED liarVars
LSuspectFenced(n, m) == Acts(n) /\ SuspectFenced(n, m) /\ UNCHANGED liarVars
LWarmBoot(n) == Acts(n) /\ WarmBoot(n) /\ UNCHANGED liarVars
LBroadcastCommand(n) == Acts(n) /\ BroadcastCommand(n) /\ UNCHANGED liarVars
LReceiveCommand(n, msg) == Acts(n) /\ ReceiveCommand(n, msg) /\ UNCHANGED liarVars
LHandOver(m, r) == Acts(m) /\ HandOver(m, r) /\ UNCHANGED liarVars
LTakeHandOver(r, h) == Acts(r) /\ TakeHandOver(r, h) /\ UNCHANGED liarVars
LFence(m, n) == Acts(m) /\ Fence(m, n) /\ UNCHANGED liarVars
LReadmit(m, n) == Acts(m) /\ Readmit(m, n) /\ UNCHANGED liarVars

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* A crash of the liar ends its lies; it restarts (Restart) as any node does, honest.
LCrash(n) ==
    /\ Crash(n)
    /\ lying' = (lying /\ n # Liar)
    /\ forged' = IF \A x \in Nodes \ {n} : ~alive[x] THEN {} ELSE forged
    /\ UNCHANGED <<fencedByHandOver, leftTakeOver, behindTakeOver>>

LRestart(n) == Restart(n) /\ UNCHANGED liarVars

\* Every epoch up to a lap above the highest a node holds (the liar's messages' range).
ForgeableEpochs == 1..(MaxEpochOf({epoch[x] : x \in Nodes}) + N)

LiarNext ==
    \/ \E x \in Nodes, e \in ForgeableEpochs : ForgeCommand(x, e)
    \/ \E x, r \in Nodes, e \in ForgeableEpochs, excl \in BOOLEAN :
          ForgeHandOver(x, r, e, excl)

\* The protocol's steps but two, which a mutant replaces: the declaration of a Master that
\* left, and the receipt of the liar's messages.
LElectionNext ==
    \/ \E n, m \in Nodes : LSuspect(n, m)
    \/ \E n \in Nodes : LBecomeMaster(n)
    \/ \E n \in Nodes, e \in {epoch[x] : x \in Nodes} : Reclaim(n, e)
    \/ \E n \in Nodes : LWarmBoot(n)
    \/ \E n \in Nodes : LBroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : LReceiveCommand(n, msg)
    \/ \E m, r \in Nodes : LHandOver(m, r)
    \/ \E r \in Nodes, h \in handOvers : LTakeHandOver(r, h)
    \/ \E m, n \in Nodes : LFence(m, n)
    \/ \E n, m \in Nodes : LSuspectFenced(n, m)
    \/ \E m, n \in Nodes : LReadmit(m, n)

LProtocolNext ==
    \/ LElectionNext
    \/ \E n, m \in Nodes : SuspectLeft(n, m)
    \/ \E x \in Nodes, c \in forged : ReceiveForged(x, c)

LEnvironmentNext ==
    \/ \E n \in Nodes : LCrash(n)
    \/ \E n \in Nodes : LRestart(n)

LNext == LProtocolNext \/ LiarNext \/ LEnvironmentNext

\* MasterElection's fairness, with the declaration of a Master that left and the reclaim
\* as fair as the take-over. The liar's messages need not arrive.
LFairness ==
    /\ \A n, m \in Nodes : WF_allVars(~alive[m] /\ LSuspect(n, m))
    /\ \A n, m \in Nodes : WF_allVars(LSuspectFenced(n, m))
    /\ \A n, m \in Nodes : WF_allVars(SuspectLeft(n, m))
    /\ \A n \in Nodes : WF_allVars(LBecomeMaster(n))
    /\ \A n \in Nodes : WF_allVars(\E e \in {epoch[x] : x \in Nodes} : Reclaim(n, e))
    /\ WF_allVars(\E n \in Nodes : LWarmBoot(n))
    /\ \A n \in Nodes : WF_allVars(LBroadcastCommand(n))
    /\ \A n \in Nodes : WF_allVars(\E msg \in msgs : LReceiveCommand(n, msg))
    /\ \A r \in Nodes : WF_allVars(\E h \in handOvers : LTakeHandOver(r, h))

LSpec == LInit /\ [][LNext]_allVars
LFairSpec == LSpec /\ LFairness

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* Rule (1): no correct node is fenced by a hand-over, a view the liar wrote in another
\* node's name.
NoFenceInAnotherNameInv == \A x \in Correct : ~fencedByHandOver[x]

\* One running Master is the Master of every running node's view, in its epoch (the liar,
\* once it stopped lying, counts as any node, and may be that Master).
Agreed ==
    \E m \in Nodes :
        /\ alive[m]
        /\ role[m] = "Master"
        /\ \A x \in Nodes : alive[x] => leader[x] = m /\ epoch[x] = epoch[m]

\* Rule (2): once the liar has stopped lying (it crashed, and restarted honest) and every
\* node is running for good, eventually the cluster agrees on a Master for good.
AgreementLiveness ==
    (<>~lying /\ <>[](\A n \in Nodes : alive[n])) => <>[]Agreed

=============================================================================
