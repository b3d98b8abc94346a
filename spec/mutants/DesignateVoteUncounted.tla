------------------------ MODULE DesignateVoteUncounted ------------------------
(***************************************************************************)
(* Mutant of Designate: the ground's vote not counted in the take-over's   *)
(* quorum (rule 4 without it), as if the ground were no member of a view   *)
(* with an even number of members for a decision. In the 2|2 cut the       *)
(* ground designates PN3; PN3 holds the vote and its lease, PN1 resigns    *)
(* after the tie grace, but PN3's and PN4's two declarations never make    *)
(* the three an exclusion of PN1 needs: no Master ever again. TLC must     *)
(* report DesignateLiveness violated in MCDesignate (exit 13).             *)
(***************************************************************************)
EXTENDS MCDesignate

MutantNext == NextBy(GroundCount, ForVote, 0)

MutantSpec ==
    /\ Init /\ [][MutantNext]_vars
    /\ <>[](TickMatters /\ ~\E d \in Nodes : TakeOverEnabledBy(GroundCount, ForVote, 0, d))
          => []<><<TickStep>>_vars
    /\ \A d \in Nodes :
          <>[](TakeOverEnabledBy(GroundCount, ForVote, 0, d)) => []<><<TakeOverStep(d)>>_vars
=============================================================================
