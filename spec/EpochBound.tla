----------------------------- MODULE EpochBound -----------------------------
(***************************************************************************)
(* Fault model 3, in time: how far a correct node lets its epoch be moved  *)
(* by one value-faulty node (docs/fault-model.md, "Fault model 3" and      *)
(* "Authority by role"). ValueFault.tla has no time, so its bound is a lap *)
(* of the succession per Command (MayCommand); the                         *)
(* runtime's grows a lap per heartbeat period (NodeProtocol::              *)
(* adoptable_epoch, command_problem, corroborated_bound, the newer_epoch_  *)
(* reclaim). This spec states that bound with time, boots and restarts,    *)
(* heartbeats that report epochs, take-overs and reclaims, and a liar that *)
(* sends heartbeats and Commands of any epoch the wire carries.            *)
(*                                                                         *)
(* Epochs go round Priority: Owner(e) = Priority[((e - 1) % Lap) + 1], a   *)
(* lap being Len(Priority) epochs. The wire carries epochs up to MaxEpoch  *)
(* (kMaxEpoch); MaxAdoptable = MaxEpoch - Lap (max_adoptable_epoch).       *)
(*                                                                         *)
(* One node, Liar, is value-faulty. Its heartbeats report any epoch up to  *)
(* MaxEpoch; its Commands carry any epoch it owns up to MaxEpoch (a        *)
(* Command of another's epoch is unauthorized; what else a Command says is *)
(* ValueFault.tla's business, and here every Command of the liar's passes  *)
(* it). It has no state: any number of its messages may arrive at any      *)
(* time. Every other node is correct and follows the rules below.          *)
(*                                                                         *)
(* The rules, for a correct node n (the ones a mutant replaces are         *)
(* operators passed to NextBy):                                            *)
(*  - Knowing its epoch (Knows; knows_epoch). n knows its epoch once it    *)
(*    adopted a Command since it booted or opened an epoch itself (the     *)
(*    initial Master's boot switch, a take-over, a reclaim). A node that   *)
(*    booted or restarted knows none: it may have been down for any time.  *)
(*  - The ceiling (Ceiling, CeilingAfter). A node that knows its epoch     *)
(*    adopts a Command of an epoch up to ceiling[n], which grows a lap at  *)
(*    every period (Tick). Opening epoch o sets it to o + Lap. Adopting a  *)
(*    Command of epoch e sets it to e + Lap, but never above what it was:  *)
(*    so a run of Commands, each a lap above the last, moves n no further  *)
(*    within a period than one Command could.                              *)
(*  - The first Command (FirstBound, Corroborated). A node that knows no   *)
(*    epoch follows a Command of epoch e only when e is at most what the   *)
(*    nodes but its sender corroborate: its own saved epoch plus a lap     *)
(*    plus a lap per period since it booted, or an epoch another node's    *)
(*    heartbeat reported since it booted plus a lap plus a lap per period  *)
(*    since that heartbeat (cc). Its ceiling is then e + Lap, never above  *)
(*    that bound.                                                          *)
(*  - The width (WidthOk, OpenOk). No node adopts an epoch above           *)
(*    MaxAdoptable: a Command of one is refused as proof against its       *)
(*    sender ("no Master opens it"). And no correct node opens one, by a   *)
(*    take-over or a reclaim, as the runtime's warm boot does not (past    *)
(*    MaxAdoptable only a cold start brings the cluster back).             *)
(*  - Reclaim (newer_epoch_). A Master that hears a heartbeat of a newer   *)
(*    epoch x within its bound, whose owner it holds failed or is itself   *)
(*    (an epoch of its own it never opened: a hand-over a liar made in its *)
(*    name), moves past it MissLimit periods later: it opens the next      *)
(*    epoch it owns above x. A take-over by a node that knows its epoch    *)
(*    may open above an epoch a voter acknowledges within its bound.       *)
(*                                                                         *)
(* Abstractions. No views or configurations. A take-over (BecomeMaster) is *)
(* any correct processing node's that is not Master, has listened          *)
(* MissLimit periods since it booted or was commanded since, and does not  *)
(* wait (a restarted node that no Command reached yet claims nothing); a   *)
(* readmission (ReadmitBy) is any correct Master's, into an epoch of its   *)
(* own or handed to any processing node; at most MaxTakeOvers of the two   *)
(* together; the failure detector may hold any other node                  *)
(* failed (fault model 2), so a Master may move past any node's epoch. A   *)
(* correct Master's Command reaches any correct node at any time. Each     *)
(* Tick delivers every correct node's heartbeat of the period to every     *)
(* other (one may arrive earlier): the correct nodes hear each other       *)
(* within a period, as fault model 3 alone assumes. So a booting node      *)
(* hears another correct node before MissLimit periods pass, and the       *)
(* runtime's clause that lets the sender's own heartbeats corroborate its  *)
(* Command once a node heard no other for miss_limit periods is never      *)
(* taken; the spec leaves it out (with it, a node that hears only the liar *)
(* follows it anywhere below the width: by design). The liar's heartbeats  *)
(* may report any epoch, so they corroborate any Command of a correct      *)
(* Master's; the spec keeps no term of theirs. A restart is one step, and  *)
(* keeps the node's saved epoch (Durable.tla); there are at most MaxBoots  *)
(* boots of nodes that know no epoch, counting those at the start (every   *)
(* correct node but a correct first Master). Time is MaxPeriods Ticks.     *)
(*                                                                         *)
(* Properties, about the correct nodes:                                    *)
(*  - TopLapInv: no correct node goes by an epoch within a lap of          *)
(*    MaxEpoch. The wire never runs out (a take-over above any correct     *)
(*    node's epoch is within it), and the width check never refuses a      *)
(*    correct Master's Command as proof (it refuses only epochs above      *)
(*    MaxAdoptable).                                                       *)
(*  - LapPerPeriodInv: no correct node's epoch is more than                *)
(*    Lap * (1 + now + boots) above H, the highest epoch a correct node    *)
(*    opened by a take-over or a readmission (the image's epoch 1 before   *)
(*    any). The liar                                                       *)
(*    moves the correct nodes a lap a period, and a lap per boot (a        *)
(*    booting node follows a Command a lap above what the others report),  *)
(*    never by sending more. A reclaim needs no allowance (ASSUME          *)
(*    MissLimit >= 2): the epoch it moves past is within its Master's      *)
(*    bound when heard, and it opens at most a lap above it two periods    *)
(*    later. This excludes the shapes keel-sim's liar found: a node that   *)
(*    booted in an epoch far above every correct node's (seed 12942: ST1   *)
(*    followed the liar's epoch 4,405,000 while the others were at 1, and  *)
(*    no correct Master reached it), and a Master moved there by one       *)
(*    heartbeat (seed 12).                                                 *)
(*                                                                         *)
(* What TLC shows (MCEpochBound.tla has the model, the mutants and the     *)
(* witnesses; one worker): both properties hold in MCEpochBound, PN3 the   *)
(* liar, MaxEpoch 12, two periods, one restart, one take-over or          *)
(* readmission: 22,121 states; with two of them, 67,087. By hand, without *)
(* ReadmitBy, they held with three periods (32,593 states), with PN2 the   *)
(* liar and MaxEpoch 15, with MaxEpoch 19, and with PN1, the first Master, *)
(* the liar and MaxEpoch 19 (MCEpochBound.tla has the counts).             *)
(* Each rule binds: without the first Command's bound                      *)
(* (EpochBoundNoBootBound), without the per-period cap                     *)
(* (EpochBoundNoPeriodCap), with a node that opened its epoch counted as   *)
(* knowing none (EpochBoundOpenedUnknown, keel-sim's                       *)
(* unbounded-master-epoch), and with the ceiling reset by every adoption   *)
(* (EpochBoundPerCommand), LapPerPeriodInv fails; with take-overs and      *)
(* reclaims that may open any epoch (EpochBoundTopLapOpens, readmissions  *)
(* still held), or readmissions that may (EpochBoundReadmitOpens),        *)
(* TopLapInv.                                                             *)
(*                                                                         *)
(* The runtime (core/fsm/node_protocol.cpp at 81049c4) differed from these *)
(* rules in four places, each fixed since (spec/README.md, "EpochBound"):  *)
(*  - adoptable_epoch counted from the epoch last adopted, so a run of     *)
(*    Commands, each a lap above the last, moved a node any distance in a  *)
(*    period (EpochBoundPerCommand; 100 Commands of a liar PN1 moved PN2   *)
(*    from 1 to 301 in under a millisecond). NodeProtocol::note_epoch now  *)
(*    re-anchors the bound only where that lowers it, as CeilingAfter.     *)
(*  - corroborated_epoch counted the periods since boot above the highest  *)
(*    epoch heard since, a waiting node's periods twice (by hand,          *)
(*    LapPerPeriodInv failed with MaxEpoch 19). corroborated_bound now     *)
(*    counts each report from when it was heard, as Corroborated does.     *)
(*  - take_over and the reclaim opened the next epoch whatever it was      *)
(*    (EpochBoundTopLapOpens; PN2, Master of 16,777,211, moved past a      *)
(*    liar's 16,777,212 to 16,777,214, refused by every node as proof).    *)
(*    Neither opens one beyond MaxAdoptable now (OpenOk;                   *)
(*    take_overs_refused).                                                 *)
(*  - a readmission or hand-over opened the next epoch whatever it was     *)
(*    (EpochBoundReadmitOpens; PN2, Master of 16,777,211, handed the view  *)
(*    to PN1 in 16,777,213). None opens one beyond MaxAdoptable now        *)
(*    (ReadmitBy's OpenOp; readmissions_refused).                          *)
(***************************************************************************)
EXTENDS Integers, FiniteSets, Sequences

CONSTANTS
    Nodes,        \* every node: the processing nodes and the others (Storage, interface)
    Priority,     \* the processing nodes in succession order; Priority[1] is the first
                  \*   Master, Owner(e) the one node that may be Master in epoch e
    Liar,         \* the value-faulty node; every other node is correct
    MaxEpoch,     \* the wire's epoch width (kMaxEpoch)
    MissLimit,    \* heartbeat periods: a booting node listens this long before it may act,
                  \*   a Master waits this long before it moves past a newer epoch
    MaxPeriods,   \* the model's time: at most this many Ticks
    MaxBoots,     \* at most this many boots of correct nodes that know no epoch (the
                  \*   initial ones of the nodes but a correct first Master, and restarts)
    MaxTakeOvers  \* at most this many take-overs and readmissions by correct nodes

Lap == Len(Priority)
Processing == {Priority[i] : i \in 1..Lap}
Correct == Nodes \ {Liar}
MaxAdoptable == MaxEpoch - Lap

ASSUME NodesAssumption ==
    /\ Lap >= 1 /\ Cardinality(Processing) = Lap
    /\ Processing \subseteq Nodes
    /\ Liar \in Nodes
    /\ Cardinality(Correct) >= 2
ASSUME BudgetAssumption ==
    /\ MaxEpoch \in Nat /\ MaxAdoptable >= 1
    /\ {MaxPeriods, MaxBoots, MaxTakeOvers} \subseteq Nat
    \* LapPerPeriodInv's reclaim argument: at least two periods between hearing an epoch
    \* and moving past it.
    /\ MissLimit \in Nat /\ MissLimit >= 2

\* The owner of epoch e >= 1, a node's place in the succession, and the first epoch above
\* e that n owns (Topology::next_epoch).
Owner(e) == Priority[((e - 1) % Lap) + 1]
Rank(n) == CHOOSE i \in 1..Lap : Priority[i] = n
NextOwnedAbove(n, e) == e + 1 + ((Rank(n) - ((e % Lap) + 1)) % Lap)

Min(a, b) == IF a <= b THEN a ELSE b
Max(a, b) == IF a >= b THEN a ELSE b
MaxOf(S) == CHOOSE x \in S : \A y \in S : y <= x

\* A bound, as the spec keeps it: no bound above MaxAdoptable is ever used (every Command
\* above it is refused first), so a bound saturates there and the state space is finite.
Capped(b) == Min(b, MaxAdoptable)

\* The epochs the wire carries: what the liar may say.
WireEpochs == 1..MaxEpoch
\* The epochs a liar's Command may carry: its own (another's is unauthorized).
LiarCommandEpochs == {e \in WireEpochs : Liar \in Processing /\ Owner(e) = Liar}

VARIABLES
    now,        \* periods since the start (Ticks so far)
    epoch,      \* [Correct -> Nat]: the epoch the node goes by (saved: a restart keeps it)
    master,     \* [Correct -> BOOLEAN]: Master of its epoch (it opened it, since it booted)
    commanded,  \* [Correct -> BOOLEAN]: it adopted a Command since it booted (commanded_)
    opened,     \* [Correct -> BOOLEAN]: it opened an epoch since it booted (mastered_,
                \*   or the initial Master's role)
    restarted,  \* [Correct -> BOOLEAN]: it booted from its saved state (restarted_)
    listened,   \* [Correct -> 0..MissLimit]: periods since it booted (saturates)
    ceiling,    \* [Correct -> Nat]: the highest epoch it adopts now, if it knows its epoch
    cc,         \* [Correct -> [Correct -> Nat]]: what each correct node corroborates, for
                \*   the first Command after a boot: cc[n][m] is the highest epoch m's
                \*   heartbeats reported since n booted, plus a lap, plus a lap per period
                \*   since that heartbeat (0: none heard); cc[n][n] is n's saved epoch plus
                \*   a lap, plus a lap per period since n booted
    newer,      \* [Correct -> Nat]: a newer epoch this Master heard and will move past (0:
                \*   none; newer_epoch_)
    newerAge,   \* [Correct -> 0..MissLimit]: periods since it noted it (saturates)
    boots,      \* boots of correct nodes that knew no epoch so far
    takeOvers,  \* take-overs and readmissions so far
    hMax,       \* ghost: H, the highest epoch a correct node opened by a take-over or a
                \*   readmission (1: the
                \*   image's)
    witnessed   \* ghost: SUBSET {"bootCorroborated", "ownPassed", "readmitted"}: what witnesses
                \*   name happened (MCEpochBound.tla)

vars == <<now, epoch, master, commanded, opened, restarted, listened, ceiling, cc, newer,
          newerAge, boots, takeOvers, hMax, witnessed>>
nodeVars == <<epoch, master, commanded, opened, restarted, listened, ceiling, cc, newer,
              newerAge>>
ghostVars == <<hMax, witnessed>>

TypeOK ==
    /\ now \in 0..MaxPeriods
    /\ epoch \in [Correct -> 1..(MaxEpoch + Lap)]
    /\ master \in [Correct -> BOOLEAN]
    /\ commanded \in [Correct -> BOOLEAN]
    /\ opened \in [Correct -> BOOLEAN]
    /\ restarted \in [Correct -> BOOLEAN]
    /\ listened \in [Correct -> 0..MissLimit]
    /\ ceiling \in [Correct -> 0..MaxEpoch]
    /\ cc \in [Correct -> [Correct -> 0..MaxEpoch]]
    /\ newer \in [Correct -> 0..MaxEpoch]
    /\ newerAge \in [Correct -> 0..MissLimit]
    /\ boots \in 0..MaxBoots
    /\ takeOvers \in 0..MaxTakeOvers
    /\ hMax \in 1..(MaxEpoch + Lap)
    /\ witnessed \subseteq {"bootCorroborated", "ownPassed", "readmitted"}

(***************************************************************************)
(* The rules (each a parameter of NextBy, so a mutant replaces one)        *)
(***************************************************************************)

\* n knows its epoch: it adopted a Command since it booted, or opened an epoch itself.
Knows(n) == commanded[n] \/ opened[n]

\* The highest epoch n, knowing its epoch, adopts now.
Ceiling(n) == Capped(ceiling[n])

\* What the nodes but sender s corroborate, for n's first Command after a boot: its own
\* saved epoch's term and each other node's. The liar's heartbeats may have reported any
\* epoch, so they corroborate any Command of a correct Master's (the spec keeps no term of
\* the liar's: it could always have sent one just before). For the liar's Commands, the
\* correct nodes' terms. (The runtime lets the sender's own heartbeats count once n heard
\* no other node for MissLimit periods since it booted; heartbeats between correct nodes
\* arrive within a period here, so that clause is never taken and the spec leaves it out.)
Corroborated(n, s) ==
    IF s # Liar THEN MaxAdoptable ELSE Capped(MaxOf({cc[n][m] : m \in Correct}))
\* A node that knows no epoch follows a Command of epoch e from s only within that.
FirstBound(n, s, e) == e <= Corroborated(n, s)

\* n's ceiling after it adopts a Command of epoch e from s: a lap above e, never above the
\* bound e passed (its ceiling, or for a first Command what the others corroborate). A
\* Command of the epoch it goes by changes nothing (the runtime's anchor moves only with
\* the epoch, note_epoch); for a node that knew none, its saved epoch's term.
CeilingAfter(n, s, e) ==
    IF e = epoch[n] THEN (IF Knows(n) THEN ceiling[n] ELSE cc[n][n])
    ELSE IF Knows(n) THEN Min(ceiling[n], Capped(e + Lap))
    ELSE Min(Corroborated(n, s), Capped(e + Lap))

\* The width: no epoch above MaxAdoptable is adopted, nor opened by a correct node.
WidthOk(e) == e <= MaxAdoptable
OpenOk(o) == o <= MaxAdoptable

(***************************************************************************)
(* Correct nodes                                                           *)
(***************************************************************************)

\* The highest epoch n adopts now (adoptable_epoch): its ceiling if it knows its epoch,
\* else the width alone (its first Command is bound by FirstBound besides).
AdoptableBy(KnowsOp(_), CeilingOp(_), n) ==
    IF KnowsOp(n) THEN CeilingOp(n) ELSE MaxAdoptable

\* n adopts a Command of epoch e from s (not stale: a Command of an older epoch is dropped
\* unread). Checked in the runtime's order: the width (a Command above it is refused as
\* proof against its sender: only the liar's, since TopLapInv holds), a first Command's
\* corroboration, the bound (a Command that fails either is dropped as ahead: no evidence).
\* A refused or dropped Command changes nothing here. A Master steps down.
ReceiveCommandBy(KnowsOp(_), FirstOk(_, _, _), CeilingOp(_), CeilingAfterOp(_, _, _),
                 n, s, e) ==
    /\ e >= epoch[n]
    /\ WidthOk(e)
    /\ ~KnowsOp(n) => FirstOk(n, s, e)
    /\ e <= AdoptableBy(KnowsOp, CeilingOp, n)
    /\ epoch' = [epoch EXCEPT ![n] = e]
    /\ master' = [master EXCEPT ![n] = @ /\ e = epoch[n]]
    /\ commanded' = [commanded EXCEPT ![n] = TRUE]
    /\ ceiling' = [ceiling EXCEPT ![n] = CeilingAfterOp(n, s, e)]
    /\ newer' = [newer EXCEPT ![n] = IF master'[n] THEN @ ELSE 0]
    /\ witnessed' =
          witnessed \cup (IF restarted[n] /\ ~KnowsOp(n) /\ e > cc[n][n]
                          THEN {"bootCorroborated"} ELSE {})
    /\ UNCHANGED <<now, opened, restarted, listened, cc, newerAge, boots, takeOvers, hMax>>

\* The nodes a Master may hold failed: any other (the liar on the evidence of a Command it
\* refused, a correct node that restarted on its own word or, fault model 2, one whose
\* heartbeats it lost).
HeldFailed(n) == Nodes \ {n}

\* n receives a heartbeat of s's that reports epoch e: a correct node's is what it
\* corroborates for n's first Command. A Master notes a newer epoch within its bound whose
\* owner it holds failed, or owns itself (an epoch of its own it never opened); it moves
\* past it MissLimit periods later (Reclaim), if the epoch it would open is one it may open.
\* (Noting is a choice here: whether the Master holds the owner failed is not modelled.)
NoteNewerBy(KnowsOp(_), CeilingOp(_), OpenOp(_), n, e) ==
    \/ /\ master[n]
       /\ e > epoch[n] /\ e > newer[n]
       /\ e <= AdoptableBy(KnowsOp, CeilingOp, n)
       /\ Owner(e) \in {n} \cup HeldFailed(n)
       /\ OpenOp(NextOwnedAbove(n, e))
       /\ newer' = [newer EXCEPT ![n] = e]
       /\ newerAge' = [newerAge EXCEPT ![n] = 0]
    \/ UNCHANGED <<newer, newerAge>>
ReceiveHeartbeatBy(KnowsOp(_), CeilingOp(_), OpenOp(_), n, s, e) ==
    /\ cc' = IF s = Liar THEN cc ELSE [cc EXCEPT ![n][s] = Max(@, Capped(e + Lap))]
    /\ NoteNewerBy(KnowsOp, CeilingOp, OpenOp, n, e)
    /\ UNCHANGED <<now, epoch, master, commanded, opened, restarted, listened, ceiling,
                   boots, takeOvers>>
    /\ UNCHANGED ghostVars

\* A Master moves past the newer epoch it noted MissLimit periods ago (the owner stayed
\* unheard, or it is its own): it opens the next epoch it owns above it.
Reclaim(m) ==
    /\ master[m]
    /\ newer[m] > epoch[m]
    /\ newerAge[m] >= MissLimit
    /\ LET o == NextOwnedAbove(m, newer[m]) IN
          /\ epoch' = [epoch EXCEPT ![m] = o]
          /\ ceiling' = [ceiling EXCEPT ![m] = Capped(o + Lap)]
    /\ newer' = [newer EXCEPT ![m] = 0]
    /\ witnessed' = witnessed \cup (IF Owner(newer[m]) = m THEN {"ownPassed"} ELSE {})
    /\ UNCHANGED <<now, master, commanded, opened, restarted, listened, cc, newerAge, boots,
                   takeOvers, hMax>>

\* n takes over (MasterElection's BecomeMaster, NodeProtocol::take_over): a correct
\* processing node that is not Master, has listened MissLimit periods since it booted or
\* was commanded since, and does not wait for a Command after a restart. It opens the next
\* epoch it owns above its own, or, if it knows its epoch, above an epoch a voter
\* acknowledges that is within its bound (a liar's acknowledgement says any); never one
\* it may not open.
BecomeMasterBy(KnowsOp(_), CeilingOp(_), OpenOp(_), n) ==
    /\ n \in Processing
    /\ ~master[n]
    /\ commanded[n] \/ (~restarted[n] /\ listened[n] >= MissLimit)
    /\ takeOvers < MaxTakeOvers
    /\ LET bound == AdoptableBy(KnowsOp, CeilingOp, n)
           acked == IF KnowsOp(n) THEN {x \in (epoch[n] + 1)..bound : Owner(x) # n} ELSE {}
       IN  \E above \in {0} \cup acked :
              LET o == NextOwnedAbove(n, Max(epoch[n], above)) IN
              /\ OpenOp(o)
              /\ epoch' = [epoch EXCEPT ![n] = o]
              /\ ceiling' = [ceiling EXCEPT ![n] = Capped(o + Lap)]
              /\ hMax' = Max(hMax, o)
    /\ master' = [master EXCEPT ![n] = TRUE]
    /\ opened' = [opened EXCEPT ![n] = TRUE]
    /\ newer' = [newer EXCEPT ![n] = 0]
    /\ takeOvers' = takeOvers + 1
    /\ UNCHANGED <<now, commanded, restarted, listened, cc, newerAge, boots, witnessed>>

\* Master m readmits a node (NodeProtocol::consider_readmission; Rejoin.tla): it opens an
\* epoch for the readmission, the next it owns above its own (ReadmitSwitch), or hands the
\* view to r, the Master of the configuration readmitted into, in the next epoch r owns
\* above m's (HandOverSwitch): m adopts it first (its own Command) and is a Master no more,
\* and r, a correct node whose bound admits it, adopts it and becomes its Master (the
\* handed Command; a liar r may do anything). Either opens an epoch, so only one it may
\* open (OpenOp: a readmission that would open one beyond MaxAdoptable is not made;
\* readmissions_refused). Who is readmitted is not modelled; a readmission counts against
\* MaxTakeOvers, as every epoch a correct node opens, and moves H (hMax) as a take-over does.
ReadmitBy(OpenOp(_), m) ==
    /\ master[m]
    /\ takeOvers < MaxTakeOvers
    /\ \E r \in Processing :
          LET o == NextOwnedAbove(r, epoch[m])
              \* r, handed the view, adopts it (a correct node, within its bound).
              takes == r # m /\ r \in Correct /\ o >= epoch[r]
                       /\ o <= AdoptableBy(Knows, Ceiling, r)
          IN
          /\ OpenOp(o)
          /\ epoch' = [x \in Correct |-> IF x = m \/ (x = r /\ takes) THEN o ELSE epoch[x]]
          /\ master' = [x \in Correct |-> IF x = m THEN r = m
                                          ELSE IF x = r /\ takes THEN TRUE ELSE master[x]]
          /\ ceiling' = [x \in Correct |-> IF x = m \/ (x = r /\ takes) THEN Capped(o + Lap)
                                           ELSE ceiling[x]]
          /\ commanded' = [x \in Correct |-> commanded[x] \/ (x = r /\ takes)]
          /\ newer' = [x \in Correct |-> IF x = m \/ (x = r /\ takes) THEN 0 ELSE newer[x]]
          /\ hMax' = Max(hMax, o)
    /\ takeOvers' = takeOvers + 1
    /\ witnessed' = witnessed \cup {"readmitted"}
    /\ UNCHANGED <<now, opened, restarted, listened, cc, newerAge, boots>>

\* A heartbeat period ends. Every bound grows by a lap; every correct node has heard each
\* other correct node's heartbeat of the period (its epoch now); the periods since a boot
\* and since a noted newer epoch grow.
Tick ==
    /\ now < MaxPeriods
    /\ now' = now + 1
    /\ ceiling' = [n \in Correct |-> IF ceiling[n] > 0 THEN Capped(ceiling[n] + Lap) ELSE 0]
    /\ cc' = [n \in Correct |->
                [m \in Correct |->
                    LET aged == IF cc[n][m] > 0 THEN Capped(cc[n][m] + Lap) ELSE 0
                    IN  IF m = n THEN aged ELSE Max(aged, Capped(epoch[m] + Lap))]]
    /\ listened' = [n \in Correct |-> Min(listened[n] + 1, MissLimit)]
    /\ newerAge' = [n \in Correct |-> Min(newerAge[n] + 1, MissLimit)]
    /\ UNCHANGED <<epoch, master, commanded, opened, restarted, newer, boots, takeOvers>>
    /\ UNCHANGED ghostVars

(***************************************************************************)
(* Environment                                                             *)
(***************************************************************************)

\* n restarts: it keeps its saved epoch and knows none; it is no Master, and has heard no
\* one since it booted.
Restart(n) ==
    /\ boots < MaxBoots
    /\ boots' = boots + 1
    /\ master' = [master EXCEPT ![n] = FALSE]
    /\ commanded' = [commanded EXCEPT ![n] = FALSE]
    /\ opened' = [opened EXCEPT ![n] = FALSE]
    /\ restarted' = [restarted EXCEPT ![n] = TRUE]
    /\ listened' = [listened EXCEPT ![n] = 0]
    /\ ceiling' = [ceiling EXCEPT ![n] = 0]
    /\ cc' = [cc EXCEPT ![n] = [m \in Correct |->
                                   IF m = n THEN Capped(epoch[n] + Lap) ELSE 0]]
    /\ newer' = [newer EXCEPT ![n] = 0]
    /\ newerAge' = [newerAge EXCEPT ![n] = 0]
    /\ UNCHANGED <<now, epoch, takeOvers>>
    /\ UNCHANGED ghostVars

(***************************************************************************)
(* Initial state and next-state relation                                   *)
(***************************************************************************)

\* The image's view: epoch 1, whose Master, Priority[1], opened it (its boot switch); every
\* other node has booted and knows no epoch yet.
Init ==
    /\ now = 0
    /\ epoch = [n \in Correct |-> 1]
    /\ master = [n \in Correct |-> n = Priority[1]]
    /\ commanded = [n \in Correct |-> FALSE]
    /\ opened = [n \in Correct |-> n = Priority[1]]
    /\ restarted = [n \in Correct |-> FALSE]
    /\ listened = [n \in Correct |-> 0]
    /\ ceiling = [n \in Correct |-> IF n = Priority[1] THEN Capped(1 + Lap) ELSE 0]
    /\ cc = [n \in Correct |-> [m \in Correct |-> IF m = n THEN Capped(1 + Lap) ELSE 0]]
    /\ newer = [n \in Correct |-> 0]
    /\ newerAge = [n \in Correct |-> 0]
    /\ boots = Cardinality(Correct \ {Priority[1]})
    /\ takeOvers = 0
    /\ hMax = 1
    /\ witnessed = {}

ASSUME BootsAssumption == MaxBoots >= Cardinality(Correct \ {Priority[1]})

\* The next-state relation with the given rules (a mutant passes one broken).
NextBy(KnowsOp(_), FirstOk(_, _, _), CeilingOp(_), CeilingAfterOp(_, _, _), OpenOp(_)) ==
    \/ \E n \in Correct :
          \* a Command of the liar's (any epoch it owns), or of a correct Master's epoch
          \/ \E e \in LiarCommandEpochs :
                ReceiveCommandBy(KnowsOp, FirstOk, CeilingOp, CeilingAfterOp, n, Liar, e)
          \/ \E m \in Correct \ {n} :
                /\ master[m]
                /\ ReceiveCommandBy(KnowsOp, FirstOk, CeilingOp, CeilingAfterOp, n, m,
                                    epoch[m])
    \/ \E n \in Correct :
          \/ \E e \in WireEpochs :
                ReceiveHeartbeatBy(KnowsOp, CeilingOp, OpenOp, n, Liar, e)
          \/ \E m \in Correct \ {n} :
                ReceiveHeartbeatBy(KnowsOp, CeilingOp, OpenOp, n, m, epoch[m])
    \/ \E n \in Correct : Reclaim(n)
    \/ \E n \in Correct : BecomeMasterBy(KnowsOp, CeilingOp, OpenOp, n)
    \* A readmission is held to the width by its own rule (a mutant of take-overs and
    \* reclaims leaves it alone; EpochBoundReadmitOpens breaks it).
    \/ \E n \in Correct : ReadmitBy(OpenOk, n)
    \/ Tick
    \* Environment
    \/ \E n \in Correct : Restart(n)

Next == NextBy(Knows, FirstBound, Ceiling, CeilingAfter, OpenOk)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* No correct node goes by an epoch within a lap of the wire's width: every node can still
\* be overtaken by a take-over whose epoch the wire carries, and whose Command is adopted.
TopLapInv == \A n \in Correct : epoch[n] <= MaxAdoptable

\* The liar moves a correct node's epoch at most a lap a period, and a lap per boot, above
\* the highest epoch a correct node opened by a take-over: never by sending more.
LapPerPeriodInv == \A n \in Correct : epoch[n] <= hMax + Lap * (1 + now + boots)
=============================================================================
