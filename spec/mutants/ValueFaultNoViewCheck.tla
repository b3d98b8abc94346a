----------------------- MODULE ValueFaultNoViewCheck ------------------------
(***************************************************************************)
(* Mutant of ValueFault: receivers do not check the Master (no rule 3): a  *)
(* Command with authority is followed whatever view it carries. The liar   *)
(* PN1 sends a view whose configuration has another master, or that        *)
(* excludes its own master or a task's host: TLC must report               *)
(* ValidConfigInv violated (exit 12).                                      *)
(***************************************************************************)
EXTENDS MCValueFault

Unchecked(n, v) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Unchecked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
