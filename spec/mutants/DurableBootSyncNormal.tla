------------------------ MODULE DurableBootSyncNormal ------------------------
(***************************************************************************)
(* Mutant of DurableBoot: the Storage node's database is opened with       *)
(* synchronous=NORMAL (StateDb's Durability::normal, keel-store-bench's    *)
(* setting): a power loss may lose the last commits, and the boot reads    *)
(* back a version below one it told the cluster it stored: TLC must report *)
(* RecoveredInv violated (exit 12).                                        *)
(***************************************************************************)
EXTENDS MCDurableBoot

MutantSpec == BInit /\ [][BNextBy(TRUE)]_allVars
=============================================================================
