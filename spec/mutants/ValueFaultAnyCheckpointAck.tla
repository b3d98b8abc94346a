--------------------- MODULE ValueFaultAnyCheckpointAck ---------------------
(***************************************************************************)
(* Mutant of ValueFault: a checkpoint acknowledgement is taken from any    *)
(* node (rule 2 without "only from the Storage node"). The liar IF1        *)
(* acknowledges a final checkpoint still on its way to the Storage node;   *)
(* its writer acks "Prepared", the task's new host restores the older      *)
(* checkpoint, and the final one arrives after: TLC must report            *)
(* NoRegressionInv violated (exit 12).                                     *)
(***************************************************************************)
EXTENDS MCValueFault

AnyAcker(s) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, AnyAcker, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
