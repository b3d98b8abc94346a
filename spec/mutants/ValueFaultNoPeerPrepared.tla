---------------------- MODULE ValueFaultNoPeerPrepared ----------------------
(***************************************************************************)
(* Mutant of ValueFault: a node takes the Activate of its switch on its    *)
(* Master's word (no rule 4: it does not wait for its peers' "Prepared").  *)
(* The liar PN1, the Master, sends PN2 its phase change, which PN3 has not *)
(* received, then its Activate; PN2 starts t1, which PN3 still runs: TLC   *)
(* must report NoDoubleActivationInv violated (exit 12).                   *)
(***************************************************************************)
EXTENDS MCValueFault

MasterWord(n) == TRUE

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      MasterWord, Backed)]_vars
=============================================================================
