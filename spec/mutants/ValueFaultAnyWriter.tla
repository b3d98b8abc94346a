------------------------ MODULE ValueFaultAnyWriter -------------------------
(***************************************************************************)
(* Mutant of ValueFault: the Storage node stores a checkpoint write from   *)
(* any node (rule 2 without "only from a node the mission may place the    *)
(* task on"). The liar IF1 writes a newer version of a task it never runs, *)
(* and the task's next host restores it: TLC must report NoForeignStateInv *)
(* violated (exit 12).                                                     *)
(***************************************************************************)
EXTENDS MCValueFault

AnyWriterNode(s, t) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, AnyWriterNode,
                      PeersPrepared, Backed)]_vars
=============================================================================
