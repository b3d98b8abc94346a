----------------------------- MODULE MCDesignate -----------------------------
(***************************************************************************)
(* Models of Designate.                                                    *)
(*                                                                         *)
(* MCDesignate (CI): prototype3's four processing nodes PN1..PN4, every    *)
(* one a monitor, PN1 the Master, cut 2|2 for good, {PN1, PN2} |           *)
(* {PN3, PN4} (the cut came first); two designations of PN2 or PN3, each   *)
(* reaching PN2 and PN3 in SEQ order, late or never (no other node's       *)
(* admissions are read by the rules); two take-overs. Mutants              *)
(* DesignateAdmittedOnly, DesignateAtOnce, DesignateVoteUncounted and,     *)
(* cut 1|3 {PN1, PN2, PN4} | {PN3} instead, DesignateGroundTwice;          *)
(* witnesses WitnessTieBroken, WitnessVoteMoved, WitnessUnreachedStopped.  *)
(* MCDesignatePair (CI): the last two monitors, PN1 and PN2, cut apart for *)
(* good, either designated; witness WitnessLastTwo.                        *)
(* MCDesignateHeal (bench): as MCDesignate, but whole at first and the     *)
(* partition changed twice (a 2|2 or 1|3 cut, then a heal or the other     *)
(* cut): where rule 5 and rule 4's last clause come from.                  *)
(*                                                                         *)
(* No symmetry: the succession tells the nodes apart, and                  *)
(* DesignateLiveness is a liveness property.                               *)
(***************************************************************************)
EXTENDS Designate, TLC

CONSTANTS S1, S2, S3, S4
MCOrder4 == <<S1, S2, S3, S4>>

MCOrder2 == <<S1, S2>>

\* A Master whose view was made by a take-over on the ground's vote.
Backed(m) == view[m].master = m /\ view[m].joint # {}

\* Witnesses: each is an invariant TLC must find violated (manifest "witnesses").
\* The 2|2 tie broken: a Master that took over on the ground's vote runs, the tie lasting.
WitnessTieBrokenInv ==
    ~\E m \in Nodes : RunningMaster(m) /\ Backed(m) /\ conn = {{S1, S2}, {S3, S4}}
\* The vote moved: a node took over on a designation, and another node that took over
\* later, on a later designation, runs as Master.
WitnessVoteMovedInv ==
    ~\E d, e \in Nodes :
        /\ d # e /\ Backed(d) /\ Backed(e) /\ RunningMaster(e)
        /\ view[d].epoch < view[e].epoch
        /\ admitted[e] > admitted[d]
\* The first Master, which no designation reached, has stopped by its tie grace while a
\* Master that took over on the ground's vote runs.
WitnessUnreachedStoppedInv ==
    ~(/\ admitted[S1] = 0 /\ ~running[S1]
      /\ \E m \in Nodes : m # S1 /\ RunningMaster(m) /\ Backed(m))
\* The last two monitors, cut apart: one runs as Master on the ground's vote.
WitnessLastTwoInv ==
    ~\E m \in Nodes : RunningMaster(m) /\ Backed(m) /\ conn # {Nodes}
=============================================================================
