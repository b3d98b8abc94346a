---------------------- MODULE ValueFaultNoVersionBound ----------------------
(***************************************************************************)
(* Mutant of ValueFault: versions are not checked against the wire's width *)
(* (rule 1 without the version bound). The liar PN1, which the mission may *)
(* place the task on, writes a checkpoint above MaxVersion and the Storage *)
(* node keeps it: TLC must report VersionBoundInv violated (exit 12).      *)
(***************************************************************************)
EXTENDS MCValueFault

AnyVersionValue(v) == v >= 0

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, AnyVersionValue, MayCommand, Checked,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
