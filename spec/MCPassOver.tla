------------------------------ MODULE MCPassOver ------------------------------
(***************************************************************************)
(* Models of PassOver (MCPassOver.cfg, in ./keel bench specs;            *)
(* MCPassOverCrashes.cfg, in CI): the paper's prototype with a fourth      *)
(* node, so that a view has a Worker: PN1 the Master, PN2 and PN3 its      *)
(* Observers, PN4 a Worker in epoch 1 (in epoch e the owner of e is        *)
(* the Master, the owners of e+1 and e+2 the Observers, the owner of e+3   *)
(* the Worker). One hand-over, one crash (which may lose the node's        *)
(* undelivered Commands and hand-overs), no restart, no false declaration; *)
(* ElectionLiar's liar (PN1) is silent. Mutants PassOverNone and           *)
(* PassOverAtViewEpoch; witnesses WitnessPassOver and WitnessStranded.     *)
(* MCPassOverCrashes.cfg: two crashes and no hand-over (seed 11501);       *)
(* mutant PassOverInFlight, witness WitnessTwoTakeOvers.                   *)
(*                                                                         *)
(* No symmetry: the priority order tells the nodes apart, and              *)
(* PassOverLiveness is a liveness property.                                *)
(***************************************************************************)
EXTENDS PassOver

CONSTANTS PN1, PN2, PN3, PN4
MCPriority == <<PN1, PN2, PN3, PN4>>

\* Witness: a take-over passed over a member ahead that was behind, and every running
\* node follows one Master.
WitnessPassOverInv == ~(passedOver /\ Agreed)

\* Witness: the set-up of PassOverLiveness's story (seed 826): no running Master, and a
\* running Observer whose view's Master is declared has ahead of it only nodes declared or
\* behind, at least one behind, each a Worker in the view it goes by (it never takes over);
\* every other running node follows the Observer's view.
WitnessStrandedInv ==
    ~(/\ ~\E m \in Nodes : alive[m] /\ role[m] = "Master"
      /\ \E n \in Nodes :
            /\ alive[n]
            /\ role[n] = "Observer"
            /\ DeclaredGone(n)
            /\ Passed(n) # {}
            /\ Ahead(n) \subseteq suspects[n] \cup Passed(n)
            /\ \A x \in Passed(n) : role[x] = "Worker"
            /\ \A y \in Nodes : alive[y] => epoch[y] = epoch[n] \/ y \in Passed(n))
\* Witness (MCPassOverCrashes): two take-overs at once, from two views: a node passed over
\* a member behind, which took over in the older view it goes by, and both run as Masters.
WitnessTwoTakeOversInv ==
    ~(/\ passedOver
      /\ \E n, m \in Nodes :
            /\ alive[n] /\ alive[m]
            /\ role[n] = "Master" /\ role[m] = "Master"
            /\ 0 < takenFrom[m] /\ takenFrom[m] < takenFrom[n])
=============================================================================
