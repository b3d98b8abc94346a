--------------------------- MODULE TraceElection ---------------------------
(***************************************************************************)
(* Trace validation of MasterElection: the election lines of every         *)
(* processing node, merged in time order, must be a behaviour of the spec. *)
(* Each line is the spec action with the logged arguments, and the acting  *)
(* node's logged role, epoch, leader, suspects and lastCommand must equal  *)
(* the spec's after it. The guards are the spec's: a command is obeyed     *)
(* only if Fresh (the one stale-epoch check), a Master claims exactly      *)
(* NextEpoch once MasterGone and everyone Ahead is suspected, or passed   *)
(* over for going by an older epoch (PassOver).                            *)
(*                                                                         *)
(* Hidden steps (at most MaxHidden between two lines): a Master's          *)
(* BroadcastCommand (the runtime sends commands without an election line), *)
(* and an Observer dropping a suspicion when the suspect's heartbeat       *)
(* arrives (the runtime does; the spec has no such step).                  *)
(*                                                                         *)
(* Where the runtime and the spec differ by design, the trace spec follows  *)
(* the runtime and spec/README.md says so: a command makes its receiver    *)
(* Observer or Worker as its configuration says (never Master), instead of *)
(* RoleIn; any obeyed command clears the suspicion of its sender; the C++  *)
(* boots with lastCommand 0 and records a new Master's own command when it *)
(* delivers it to itself; a restart (a simulator's env line) is the spec's *)
(* Restart without its "every running node declared it" guard, which the   *)
(* runtime's Master keeps in the switch's failed set, not in suspects.     *)
(***************************************************************************)
\* TraceElectionData is written next to this module for each trace: it defines Log (the
\* lines, a sequence of records) and the mission's constant values. Log is a definition,
\* not a CONSTANT, so that TLC evaluates it once.
EXTENDS MasterElection, TraceElectionData, Sequences, TLC

CONSTANTS
    Followers,  \* the nodes outside the succession (storage, interface): they obey
                \* commands, and are never Master or Observer
    MaxHidden,  \* at most this many hidden steps between two lines
    Relax       \* diagnosis: line Relax need not match its logged variables (0: none)

ASSUME Followers \cap Nodes = {}

VARIABLES l, hidden, fepoch,  \* fepoch: [Followers -> Nat], the epoch a follower follows
          hist,                \* [Nodes -> SUBSET Nat]: the epochs each node went by
          tfenced              \* the nodes whose last Command's view excludes them

traceVars == <<l, hidden, fepoch, hist, tfenced>>

NextIs(a) == l <= Len(Log) /\ Log[l].action = a

Matches(e) ==
    \/ l = Relax
    \/ /\ role'[e.n] = e.vrole
       /\ epoch'[e.n] = e.vepoch
       /\ leader'[e.n] = e.vleader
       /\ suspects'[e.n] = e.vsuspects
       /\ e.action \notin {"BecomeMaster", "Reclaim", "WarmBoot"} => lastCommand'[e.n] = e.vlast

\* The spec's Init, but no command obeyed yet.
TraceInit ==
    /\ alive = [n \in Nodes |-> TRUE]
    /\ role = [n \in Nodes |-> IF n = Owner(1) THEN "Master" ELSE RoleIn(n, 1)]
    /\ epoch = [n \in Nodes |-> 1]
    /\ leader = [n \in Nodes |-> Owner(1)]
    /\ suspects = [n \in Nodes |-> {}]
    /\ lastCommand = [n \in Nodes |-> 0]
    /\ msgs = {[epoch |-> 1, from |-> Owner(1)]}
    /\ handOvers = {}
    /\ boot = [n \in Nodes |-> 0]
    /\ restartEpoch = [n \in Nodes |-> 0]
    /\ crashes = 0
    /\ restarts = 0
    /\ falseSuspicions = 0
    /\ handOverCount = 0
    /\ fenced = [n \in Nodes |-> FALSE]
    /\ fenceCount = 0
    /\ l = 1
    /\ hidden = 0
    /\ fepoch = [n \in Followers |-> 1]
    /\ hist = [n \in Nodes |-> {1}]
    /\ tfenced = {}

\* A Master that learned of a newer epoch whose owner is gone claims its next epoch
\* above it: BecomeMaster from that epoch.
Reclaim(n, above) ==
    /\ alive[n]
    /\ role[n] = "Master"
    /\ above > epoch[n]
    /\ Owner(above) # n
    /\ LET e == NextEpochAbove(n, above) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, role, suspects, restartEpoch, crashes, restarts, falseSuspicions>>

\* A take-over that passes over members that go by an older epoch than the taker's
\* (NodeProtocol::diverged_members: a member that never took the view, whose Master is
\* gone; keel-sim --loss 5%, earth-observation seed 11501). The line names the members
\* passed over (`passed`) with the epoch each last said in its heartbeats (`heard`): it
\* must be below the taker's, and one the member went by (`hist`: its heartbeats say its
\* epoch; the member may have moved on since, even taken over itself, its heartbeats not
\* there yet). A member passed over at the taker's epoch or a newer one, or at an epoch it
\* never had, is rejected at the line. A line of a build that logged no epochs holds the
\* member's current epoch below the taker's. A member passed over for a newer switch of
\* the taker's view's epoch, one that never reached the taker (`newer`: its Prepared named
\* it), or for never preparing the taker's view (`unprepared`), said an epoch it went by,
\* at most the taker's (spec/DivergedView.tla's NewerSwitch and NeverPrepared; the
\* Prepared, or its absence, is TraceConfigSwitch's TakeOverEvidence's to check). The rest is the spec's BecomeMaster, with
\* the members passed over counted as suspected.
PassOver(n, passed, heard, newer) ==
    /\ newer \subseteq passed
    /\ \A m \in passed :
          /\ m # n
          /\ IF m \in newer THEN m \in DOMAIN heard /\ heard[m] \in hist[m] /\ heard[m] <= epoch[n]
             ELSE IF m \in DOMAIN heard THEN heard[m] \in hist[m] /\ heard[m] < epoch[n]
                                        ELSE epoch[m] < epoch[n]
    /\ alive[n]
    /\ role[n] # "Master"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ MasterGone(n)
    /\ Ahead(n) \subseteq suspects[n] \cup passed
    /\ LET e == NextEpoch(n) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, suspects, restartEpoch, crashes, restarts, falseSuspicions>>

\* The runtime's ReceiveCommand (see the header for how it differs).
ObeyCommand(n, msg, newRole) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.from # n
    /\ Fresh(n, msg)
    /\ newRole # "Master"
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ leader' = [leader EXCEPT ![n] = msg.from]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = msg.epoch]
    /\ role' = [role EXCEPT ![n] = newRole]
    /\ suspects' = [suspects EXCEPT ![n] = @ \ {msg.from}]
    /\ UNCHANGED <<alive, msgs, restartEpoch, crashes, restarts, falseSuspicions>>

\* A Master's own command, delivered to itself: nothing changes but lastCommand.
OwnCommand(n, e) ==
    /\ alive[n]
    /\ role[n] = "Master"
    /\ epoch[n] = e
    /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
    /\ UNCHANGED <<alive, role, epoch, leader, suspects, msgs, restartEpoch, crashes,
                   restarts, falseSuspicions>>

\* A follower obeys a command some Master of that epoch broadcast (in msgs), never one
\* older than the epoch it follows (Fresh); it follows that Master as a Worker. The
\* spec's nodes are not touched: a follower takes no part in elections.
FollowerCommand(n, msg, e) ==
    /\ n \in Followers
    /\ msg \in msgs
    /\ msg.epoch >= fepoch[n]
    /\ e.vrole = "Worker" /\ e.vepoch = msg.epoch /\ e.vleader = Owner(msg.epoch)
    /\ e.vsuspects = {} /\ e.vlast = msg.epoch
    /\ e.stepDown # "yes"  \* never Master: it steps down from nothing
    /\ fepoch' = [fepoch EXCEPT ![n] = msg.epoch]
    /\ UNCHANGED vars

\* Reintegration (spec/Rejoin.tla), as the runtime's election carries it out:
\* - the Master readmits a node into a configuration of its own: it opens its next epoch
\*   (OpenEpoch line), whose commands the others obey as any;
\* - the Master hands the view to the configuration's master r (its HandOver line, in
\*   the switch's fsm): a command of r's next epoch above its own, sent by itself. It
\*   adopts it at once and steps down (its own ReceiveCommand, stepDown); a receiver
\*   obeys it as from r (leader r), and r becomes Master of that epoch.
OpenEpochLine(n, e) ==
    /\ alive[n]
    /\ role[n] = "Master"
    /\ e = NextEpochAbove(n, epoch[n])
    /\ epoch' = [epoch EXCEPT ![n] = e]
    /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ UNCHANGED <<alive, role, leader, suspects, lastCommand, restartEpoch, crashes,
                   restarts, falseSuspicions>>

HandOverLine(m, r, e) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ r # m
    /\ e = NextEpochAbove(r, epoch[m])
    /\ msgs' = msgs \cup {[epoch |-> e, from |-> m]}
    /\ UNCHANGED <<alive, role, epoch, leader, suspects, lastCommand, restartEpoch, crashes,
                   restarts, falseSuspicions>>

\* The Master that handed the view over adopts it: r's Observer or Worker.
HandedOver(m, e, newRole) ==
    /\ alive[m]
    /\ role[m] = "Master"
    /\ [epoch |-> e, from |-> m] \in msgs
    /\ Owner(e) # m
    /\ newRole # "Master"
    /\ epoch' = [epoch EXCEPT ![m] = e]
    /\ leader' = [leader EXCEPT ![m] = Owner(e)]
    /\ lastCommand' = [lastCommand EXCEPT ![m] = e]
    /\ role' = [role EXCEPT ![m] = newRole]
    /\ UNCHANGED <<alive, suspects, msgs, restartEpoch, crashes, restarts, falseSuspicions>>

\* A node obeys a handed-over command as from the epoch's owner; the owner is Master.
ObeyHandOver(n, msg, newRole) ==
    /\ alive[n]
    /\ msg \in msgs
    /\ msg.from # n
    /\ Owner(msg.epoch) # msg.from
    /\ Fresh(n, msg)
    /\ (newRole = "Master") = (n = Owner(msg.epoch))
    /\ epoch' = [epoch EXCEPT ![n] = msg.epoch]
    /\ leader' = [leader EXCEPT ![n] = Owner(msg.epoch)]
    /\ lastCommand' = [lastCommand EXCEPT ![n] = msg.epoch]
    /\ role' = [role EXCEPT ![n] = newRole]
    /\ suspects' = [suspects EXCEPT ![n] = @ \ {msg.from}]
    /\ UNCHANGED <<alive, msgs, restartEpoch, crashes, restarts, falseSuspicions>>

Reboot(n) ==
    /\ ~alive[n]
    /\ alive' = [alive EXCEPT ![n] = TRUE]
    /\ role' = [role EXCEPT ![n] = "Worker"]
    /\ epoch' = [epoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ leader' = [leader EXCEPT ![n] = NoNode]
    /\ suspects' = [suspects EXCEPT ![n] = {}]
    /\ restartEpoch' = [restartEpoch EXCEPT ![n] = RejoinEpoch(n)]
    /\ restarts' = restarts + 1
    /\ UNCHANGED <<lastCommand, msgs, crashes, falseSuspicions>>

LineStep ==
    /\ l <= Len(Log)
    /\ LET e == Log[l] IN
        /\ CASE e.action = "Suspect" -> Suspect(e.n, e.m) /\ Matches(e)
             [] e.action = "SuspectOther" -> UNCHANGED vars /\ Matches(e)
             [] e.action = "BecomeMaster" ->
                    IF e.passed = {} THEN BecomeMaster(e.n) /\ Matches(e)
                    ELSE PassOver(e.n, e.passed, e.heard, e.newer \cup e.unprepared) /\ Matches(e)
             [] e.action = "Reclaim" -> Reclaim(e.n, e.above) /\ Matches(e)
             \* The spec's WarmBoot: every node waits (each rebooted, none commanded since),
             \* and the epoch claimed is the first n owns above every node's.
             \* A node runs fenced when the last Command it adopted excludes it (the
             \* line's `fenced`: its switch line's view); that one is idle too.
             [] e.action = "WarmBoot" ->
                    WarmBootBy(LAMBDA x : Idle(x) \/ (alive[x] /\ x \in tfenced), e.n)
                    /\ Matches(e)
             [] e.action = "ReceiveCommand" ->
                    \* The line's stepDown: it was Master before the command, and is not after.
                    /\ e.stepDown \in {"yes", "no"} =>
                          ((e.stepDown = "yes") = (role[e.n] = "Master" /\ e.vrole # "Master"))
                    /\ IF e.from = e.n
                       THEN IF Owner(e.epoch) = e.n
                            THEN OwnCommand(e.n, e.epoch) /\ Matches(e)
                            ELSE HandedOver(e.n, e.epoch, e.vrole) /\ Matches(e)
                       ELSE IF Owner(e.epoch) = e.from
                            THEN ObeyCommand(e.n, [epoch |-> e.epoch, from |-> e.from], e.vrole)
                                 /\ Matches(e)
                            ELSE ObeyHandOver(e.n, [epoch |-> e.epoch, from |-> e.from], e.vrole)
                                 /\ Matches(e)
             [] e.action = "OpenEpoch" -> OpenEpochLine(e.n, e.epoch) /\ Matches(e)
             [] e.action = "HandOver" -> HandOverLine(e.n, e.m, e.epoch)
             [] e.action = "Crash" -> Crash(e.n)
             [] e.action = "Restart" -> Reboot(e.n)
             [] e.action = "FollowerCommand" ->
                    FollowerCommand(e.n, [epoch |-> e.epoch, from |-> e.from], e)
             [] OTHER -> FALSE
        /\ e.action = "FollowerCommand" \/ UNCHANGED fepoch
        /\ tfenced' = CASE e.action = "ReceiveCommand" /\ e.fenced = "yes" -> tfenced \cup {e.n}
                         [] e.action = "ReceiveCommand" /\ e.fenced = "no" -> tfenced \ {e.n}
                         [] e.action = "WarmBoot" -> tfenced \ {e.n}
                         [] OTHER -> tfenced
        /\ l' = l + 1
        /\ hidden' = 0

HiddenBroadcast(n) ==
    /\ NextIs("ReceiveCommand") \/ NextIs("FollowerCommand")
    /\ Log[l].from = n
    /\ Log[l].epoch = epoch[n]
    /\ BroadcastCommand(n)

\* An Observer hears a node it suspected (a heartbeat), or a view readmits it: the
\* suspicion was wrong. Neither is an election line. The node's next line no longer lists
\* x, or declares x anew (readmitted, then failed again: the line lists it again).
HiddenClear(n, x) ==
    /\ l <= Len(Log)
    /\ Log[l].n = n
    /\ Log[l].action \in {"Suspect", "SuspectOther", "BecomeMaster", "ReceiveCommand"}
    /\ x \in suspects[n]
    /\ x \notin Log[l].vsuspects \/ (Log[l].action = "Suspect" /\ Log[l].m = x)
    /\ suspects' = [suspects EXCEPT ![n] = @ \ {x}]
    /\ UNCHANGED <<alive, role, epoch, leader, lastCommand, msgs, restartEpoch, crashes,
                   restarts, falseSuspicions>>

HiddenStep ==
    /\ hidden < MaxHidden
    /\ \/ \E n \in Nodes : HiddenBroadcast(n)
       \/ \E n, x \in Nodes : HiddenClear(n, x)
    /\ hidden' = hidden + 1
    /\ UNCHANGED <<l, fepoch, tfenced>>

\* The spec's safety invariants hold along the trace: a line whose step would break one
\* is not explained (the trace stops there, a mismatch at that line). The spec's
\* hand-over variables stay as they start: the runtime's hand-overs are the HandOver and
\* ReceiveCommand lines above, commands in msgs, whose boot the trace does not check. So do
\* its fence variables: no election line says a node is fenced (the switch job's Fence
\* does), so the spec's `fenced` stays FALSE; WarmBoot counts as idle, besides the nodes
\* that wait, those a Command's view excluded (tfenced, from each ReceiveCommand line's
\* `fenced`: the node's switch line of the same Command names it in `out`).
TraceNext == (LineStep \/ HiddenStep)
             /\ hist' = [x \in Nodes |-> hist[x] \cup {epoch'[x]}]
             /\ UNCHANGED <<handOvers, boot, handOverCount, fenced, fenceCount>>
             /\ OneMasterPerEpochInv' /\ MasterOwnsEpochInv' /\ NoStaleMastershipInv'

TraceNotAccepted == l <= Len(Log)
\* The same verdict without a counter-example: TLC prints the marker when a state past
\* the last line is reachable, and goes on (printing a behaviour as long as the trace
\* costs more than checking it).
TraceExplained == l <= Len(Log) \/ PrintT("keel-trace: every line explained")
NotPastRelax == l <= Relax
=============================================================================
