----------------------- MODULE ValueFaultAnyActivate ------------------------
(***************************************************************************)
(* Mutant of ValueFault: an Activate for the receiver's switch is taken    *)
(* from any node (rule 2 without "only from the master of the receiver's   *)
(* view"). The liar IF1 sends the Activate of a phase change before the    *)
(* task's old host has stopped it, and its new host starts it: TLC must    *)
(* report NoDoubleActivationInv violated (exit 12).                        *)
(***************************************************************************)
EXTENDS MCValueFault

AnySender(n, s) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      AnySender, MayAck, MayReply, MayWrite)]_vars
=============================================================================
