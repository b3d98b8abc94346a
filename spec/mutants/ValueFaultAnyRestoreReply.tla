--------------------- MODULE ValueFaultAnyRestoreReply ----------------------
(***************************************************************************)
(* Mutant of ValueFault: a restore reply is taken from any node (rule 2    *)
(* without "only from the Storage node or a node the mission may place the *)
(* task on"). The liar IF1 answers a restore with an old version: TLC must *)
(* report NoRegressionInv violated (exit 12).                              *)
(***************************************************************************)
EXTENDS MCValueFault

AnyReplier(s, t) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, AnyReplier, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
