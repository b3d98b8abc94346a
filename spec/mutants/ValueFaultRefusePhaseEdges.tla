--------------------- MODULE ValueFaultRefusePhaseEdges ---------------------
(***************************************************************************)
(* Mutant of ValueFault: a receiver checking its Master's next switch      *)
(* knows no phase edge of the decision graph (keel-sim's                   *)
(* refuse-phase-edges). The correct Master's phase change is refused as no *)
(* Master's and the Master declared failed: TLC must report                *)
(* NoHonestRefusalInv violated (exit 12).                                  *)
(***************************************************************************)
EXTENDS MCValueFault

FailureEdgesOnly(n, v) ==
    /\ Valid(v)
    /\ IsNextSwitch(n, v) =>
          /\ view[n].failed \subseteq v.failed /\ view[n].failed # v.failed
          /\ v.config = Target(view[n].config, v.failed \ view[n].failed, v.failed)

MutantSpec ==
    Init /\ [][NextBy(EpochInBounds, VersionInBounds, MayCommand, FailureEdgesOnly,
                      MayActivate, MayAck, MayReply, MayWrite,
                      PeersPrepared, Backed)]_vars
=============================================================================
