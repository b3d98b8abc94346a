------------------------------- MODULE Durable -------------------------------
(***************************************************************************)
(* The node driver's rules (core/node/driver.hpp): what a node says stands *)
(* only for what is on its disk. The protocol's specs take a node's words  *)
(* and its durable state as one; the runtime writes to a disk that may     *)
(* lose power, fill up or fail, and the driver orders the two:             *)
(*                                                                         *)
(* Rule 1: the node's state is saved before the messages of the step that  *)
(*   changed it leave. Here: a node adopts newer epochs (a Command's),     *)
(*   saves its epoch, and sends messages of the epoch it goes by; a power  *)
(*   loss takes it back to the epoch on its disk.                          *)
(* Rule 2: the Storage node's acknowledgements (and restore replies and    *)
(*   StoreCheckpoint lines: whatever tells the cluster a version is        *)
(*   stored) wait until that version is on its disk. Here: a writer makes  *)
(*   versions of its task's checkpoint and sends each; the Storage node    *)
(*   queues the newest it received (a waiting write is replaced by a newer *)
(*   one, as the persister coalesces), writes it, and only then tells; a   *)
(*   power loss loses what was queued.                                     *)
(* Rule 3: a failed write is fail-stop: what waited for it is never told,  *)
(*   and the Storage node leaves (it asks to be excluded and stops).       *)
(*                                                                         *)
(* Properties: ToldDurableInv (a version the Storage node told the         *)
(* cluster is stored is on its disk whenever it is down: a power loss or   *)
(* a fail-stop loses nothing it told) and SaidDurableInv (a running node   *)
(* never goes by an epoch below one it has sent a message of: after a      *)
(* power loss it does not follow an older Master it already left). The     *)
(* mutants mutants/DurableReleaseEarly.tla (rule 2),                       *)
(* DurableSaveAfterSend.tla (rule 1) and DurableIgnoreFailedWrite.tla      *)
(* (rule 3) are keel-sim's driver mutants release-held-early,              *)
(* save-after-send and ignore-failed-write; TLC rejects each. Witnesses    *)
(* (MCDurable.tla): the Storage node loses power after it told a version,  *)
(* a failed write stops it, and the node restarts after it spoke.          *)
(*                                                                         *)
(* The protocol's specs need these rules, and assume them: ConfigSwitch's  *)
(* `stored` is this spec's `disk` as far as the cluster was told, and      *)
(* MasterElection's persisted epoch is `saved`. Trace validation checks    *)
(* rule 2 on a restarted Storage node's Recovered lines (TraceConfigSwitch *)
(* `written`); keel-sim checks all three (ResumeLatestCheckpointInv's      *)
(* durable clause, DurableStateInv) with the same driver keel-node runs.   *)
(***************************************************************************)
EXTENDS Naturals

CONSTANTS
    MaxVersion,  \* the writer makes versions 1..MaxVersion of its task's checkpoint
    MaxEpoch,    \* the node adopts epochs up to MaxEpoch
    MaxCrashes   \* power losses, of the Storage node and the node together

VARIABLES
    made,     \* the newest version the writer made (and sent)
    net,      \* SUBSET 1..MaxVersion: checkpoint writes on their way to the Storage node
    queued,   \* the version the Storage node received and has not written yet (0: none)
    disk,     \* the version on the Storage node's disk (0: none)
    told,     \* the newest version the Storage node ever told the cluster it stores
    diskOk,   \* the Storage node's disk accepts writes
    sUp,      \* the Storage node runs
    stopped,  \* the Storage node stopped for good, for a failed write (rule 3)
    epoch,    \* the epoch the node goes by
    saved,    \* the epoch on the node's disk
    said,     \* the newest epoch the node ever sent a message of
    nUp,      \* the node runs
    rebooted, \* the node restarted at least once (history, for a witness)
    crashes

vars == <<made, net, queued, disk, told, diskOk, sUp, stopped, epoch, saved, said, nUp,
          rebooted, crashes>>

Max(a, b) == IF a >= b THEN a ELSE b

TypeOK ==
    /\ made \in 0..MaxVersion
    /\ net \subseteq 1..MaxVersion
    /\ queued \in 0..MaxVersion
    /\ disk \in 0..MaxVersion
    /\ told \in 0..MaxVersion
    /\ diskOk \in BOOLEAN /\ sUp \in BOOLEAN /\ stopped \in BOOLEAN
    /\ epoch \in 1..MaxEpoch /\ saved \in 1..MaxEpoch /\ said \in 0..MaxEpoch
    /\ nUp \in BOOLEAN /\ rebooted \in BOOLEAN
    /\ crashes \in 0..MaxCrashes

Init ==
    /\ made = 0 /\ net = {} /\ queued = 0 /\ disk = 0 /\ told = 0
    /\ diskOk = TRUE /\ sUp = TRUE /\ stopped = FALSE
    /\ epoch = 1 /\ saved = 1 /\ said = 0 /\ nUp = TRUE /\ rebooted = FALSE
    /\ crashes = 0

nodeVars == <<epoch, saved, said, nUp, rebooted>>
storageVars == <<made, net, queued, disk, told, diskOk, sUp, stopped>>

(***************************************************************************)
(* The writer and the Storage node (rules 2 and 3)                         *)
(***************************************************************************)

\* The writer's task steps and checkpoints: the new version goes to the Storage node.
Make ==
    /\ made < MaxVersion
    /\ made' = made + 1
    /\ net' = net \cup {made + 1}
    /\ UNCHANGED <<queued, disk, told, diskOk, sUp, stopped, crashes>> /\ UNCHANGED nodeVars

\* The Storage node receives a write. It keeps only a newer version than it holds or has
\* queued; a waiting write is replaced by a newer one. Rule 2: it tells nothing yet
\* (`early`: the mutant that tells at once).
ReceiveBy(v, early) ==
    /\ sUp
    /\ v \in net
    /\ net' = net \ {v}
    /\ queued' = IF v > Max(queued, disk) THEN v ELSE queued
    /\ told' = IF early /\ v > Max(queued, disk) THEN Max(told, v) ELSE told
    /\ UNCHANGED <<made, disk, diskOk, sUp, stopped, crashes>> /\ UNCHANGED nodeVars

\* The queued write lands on the disk; what waited for it is told now.
WriteOk ==
    /\ sUp
    /\ queued > 0
    /\ diskOk
    /\ disk' = queued
    /\ queued' = 0
    /\ told' = Max(told, queued)
    /\ UNCHANGED <<made, net, diskOk, sUp, stopped, crashes>> /\ UNCHANGED nodeVars

\* The queued write fails (a full or failing disk). Rule 3: nothing is told, and the
\* Storage node stops for good (`ignore`: the mutant that takes it for written and flies
\* on).
WriteFailsBy(ignore) ==
    /\ sUp
    /\ queued > 0
    /\ ~diskOk
    /\ IF ignore
       THEN /\ told' = Max(told, queued)
            /\ queued' = 0
            /\ UNCHANGED <<sUp, stopped>>
       ELSE /\ sUp' = FALSE
            /\ stopped' = TRUE
            /\ queued' = 0
            /\ UNCHANGED told
    /\ UNCHANGED <<made, net, disk, diskOk, crashes>> /\ UNCHANGED nodeVars

\* The disk fills up or fails (for good).
DiskFails ==
    /\ diskOk
    /\ diskOk' = FALSE
    /\ UNCHANGED <<made, net, queued, disk, told, sUp, stopped, crashes>> /\ UNCHANGED nodeVars

\* The Storage node loses power: what it had queued is lost.
CrashStorage ==
    /\ sUp
    /\ crashes < MaxCrashes
    /\ sUp' = FALSE
    /\ queued' = 0
    /\ crashes' = crashes + 1
    /\ UNCHANGED <<made, net, disk, told, diskOk, stopped>> /\ UNCHANGED nodeVars

\* It boots again from its disk (not after a fail-stop: its disk failed).
RestartStorage ==
    /\ ~sUp
    /\ ~stopped
    /\ sUp' = TRUE
    /\ UNCHANGED <<made, net, queued, disk, told, diskOk, stopped, crashes>> /\ UNCHANGED nodeVars

(***************************************************************************)
(* The node's own state (rule 1)                                           *)
(***************************************************************************)

\* The node adopts a newer epoch (a Command's): in memory.
Adopt ==
    /\ nUp
    /\ epoch < MaxEpoch
    /\ epoch' = epoch + 1
    /\ UNCHANGED <<saved, said, nUp, rebooted, crashes>> /\ UNCHANGED storageVars

\* The driver saves the node's state.
Save ==
    /\ nUp
    /\ saved # epoch
    /\ saved' = epoch
    /\ UNCHANGED <<epoch, said, nUp, rebooted, crashes>> /\ UNCHANGED storageVars

\* The node sends a message of the epoch it goes by (a Prepared, a heartbeat). Rule 1:
\* only once that epoch is saved (`checked`: FALSE in the mutant that sends first).
SendBy(checked) ==
    /\ nUp
    /\ checked => saved = epoch
    /\ said' = Max(said, epoch)
    /\ UNCHANGED <<epoch, saved, nUp, rebooted, crashes>> /\ UNCHANGED storageVars

\* The node loses power, and boots again from its disk.
CrashNode ==
    /\ nUp
    /\ crashes < MaxCrashes
    /\ nUp' = FALSE
    /\ crashes' = crashes + 1
    /\ UNCHANGED <<epoch, saved, said, rebooted>> /\ UNCHANGED storageVars

RestartNode ==
    /\ ~nUp
    /\ nUp' = TRUE
    /\ epoch' = saved
    /\ rebooted' = TRUE
    /\ UNCHANGED <<saved, said, crashes>> /\ UNCHANGED storageVars

NextBy(early, ignore, checked) ==
    \/ Make
    \/ \E v \in 1..MaxVersion : ReceiveBy(v, early)
    \/ WriteOk
    \/ WriteFailsBy(ignore)
    \/ DiskFails
    \/ CrashStorage
    \/ RestartStorage
    \/ Adopt
    \/ Save
    \/ SendBy(checked)
    \/ CrashNode
    \/ RestartNode

Next == NextBy(FALSE, FALSE, TRUE)

Spec == Init /\ [][Next]_vars

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* A version the Storage node told the cluster it stores is not lost when it goes down
\* (a power loss, or a fail-stop): its disk holds it, and the cluster resumes the task
\* from nothing older when it boots again (or from the writer's hand-off meanwhile).
ToldDurableInv == ~sUp => told <= disk

\* A running node goes by no epoch below one it has sent a message of.
SaidDurableInv == nUp => said <= epoch
=============================================================================
