------------------------------ MODULE DurableBoot ------------------------------
(***************************************************************************)
(* What a restarted Storage node recovers at boot (core/node/runtime.cpp  *)
(* reads StateDb::load_checkpoints into the PersistentState;               *)
(* CheckpointStore::restore and trace_recovered log one `Recovered` line   *)
(* per checkpointed task, core/fsm/checkpoint_store.cpp).                  *)
(*                                                                         *)
(* Durable.tla orders the Storage node's words after its disk (rule 2: an  *)
(* acknowledgement, a restore reply or a StoreCheckpoint line waits until  *)
(* the version it stands for is written) and proves that what it told is  *)
(* on its disk whenever it is down (ToldDurableInv). This spec adds the    *)
(* boot that reads it back, as the runtime does it:                        *)
(*  - the durability the runtime gives. StateDb opens every connection     *)
(*    (the loop's and the persister's) with journal_mode=WAL and           *)
(*    synchronous=FULL: the log is synced at every commit, so a write the  *)
(*    persister reported written (checkpoint_written, which releases what  *)
(*    waited for it) survives a power loss, and a transaction is atomic: a *)
(*    power loss during a write leaves the version before it. The queued   *)
(*    write is lost (Durable's CrashStorage). Durability::normal           *)
(*    (synchronous=NORMAL: a power loss may lose the last commits) is      *)
(*    keel-store-bench's only; mutants/DurableBootSyncNormal.tla flies it. *)
(*  - Recover (the restart, RestartStorage, with its Recovered line): the  *)
(*    Storage node reads its checkpoints back (the newest of each task:    *)
(*    the stored one, as StateDb keeps only a newer version) and serves    *)
(*    them; `recovered` is the version its Recovered line logs.            *)
(* Property: RecoveredInv, the version recovered at a boot is never below  *)
(* one the Storage node told the cluster it stored before that boot (the   *)
(* trace check `Recovered`: e.version >= written[e.t]).                    *)
(*                                                                         *)
(* Left out: a record that fails its checksum or its widths at boot is     *)
(* lost and reported (fault model 3, integrity at rest): a fault, whose    *)
(* Recovered line the trace check rejects. The host's write over a foreign *)
(* writer's (CheckpointStore::host_wins, `replaces`) may store an older    *)
(* version: only a value-faulty writer makes it (docs/fault-model.md).     *)
(***************************************************************************)
EXTENDS Durable

VARIABLES
    recovered,  \* the version the Storage node read back at its last boot (0: none)
    toldAtBoot, \* history: what it had told the cluster before that boot
    sBoots      \* history: the Storage node's restarts

bootVars == <<recovered, toldAtBoot, sBoots>>
allVars == <<vars, bootVars>>

BTypeOK ==
    /\ TypeOK
    /\ recovered \in 0..MaxVersion
    /\ toldAtBoot \in 0..MaxVersion
    /\ sBoots \in 0..MaxCrashes

BInit == Init /\ recovered = 0 /\ toldAtBoot = 0 /\ sBoots = 0

\* The Storage node loses power (Durable's CrashStorage). `normal`: the disk was opened with synchronous=NORMAL
\* (the mutant): the last commits may be lost with it, back to any earlier version.
CrashStorageBy(normal) ==
    /\ sUp
    /\ crashes < MaxCrashes
    /\ sUp' = FALSE
    /\ queued' = 0
    /\ crashes' = crashes + 1
    /\ IF normal THEN \E v \in 0..disk : disk' = v ELSE UNCHANGED disk
    /\ UNCHANGED <<made, net, told, diskOk, stopped>> /\ UNCHANGED nodeVars

\* It boots again from its disk and logs what it read back (its Recovered line).
Recover ==
    /\ RestartStorage
    /\ recovered' = disk
    /\ toldAtBoot' = told
    /\ sBoots' = sBoots + 1

\* Durable's next-state relation (its rules kept), with the power loss and the boot as
\* above.
BNextBy(normal) ==
    \/ /\ \/ Make
          \/ \E v \in 1..MaxVersion : ReceiveBy(v, FALSE)
          \/ WriteOk
          \/ WriteFailsBy(FALSE)
          \/ DiskFails
          \/ Adopt
          \/ Save
          \/ SendBy(TRUE)
          \/ CrashNode
          \/ RestartNode
       /\ UNCHANGED bootVars
    \/ CrashStorageBy(normal) /\ UNCHANGED bootVars
    \/ Recover

BNext == BNextBy(FALSE)

BSpec == BInit /\ [][BNext]_allVars

\* What a boot recovers is never below what the Storage node told before it.
RecoveredInv == recovered >= toldAtBoot
=============================================================================
