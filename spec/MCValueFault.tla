---------------------------- MODULE MCValueFault ----------------------------
(***************************************************************************)
(* HEADER                                                                  *)
(***************************************************************************)
EXTENDS ValueFault

CONSTANTS PN1, PN2, PN3, ST1, IF1, t1

MCPriority == <<PN1, PN2, PN3>>

\* The mission phases.
MCPhases == {"P1", "P2"}

\* A configuration is a phase and the processing node the graph took out (at most one);
\* a second failure leads to Safe.
MCConfigIds == [phase : MCPhases, out : {{}} \cup {{x} : x \in {PN1, PN2, PN3}}]
MCInitialConfig == [phase |-> "P1", out |-> {}]

\* The master: the first node in succession the configuration did not take out.
MCConfigMaster(c) == IF PN1 \notin c.out THEN PN1 ELSE PN2

\* Where t1 runs: PN3 in P1, PN2 in P2, or the other of the two if that one is out; the
\* Master when both are.
MCPreference(p) == IF p = "P1" THEN <<PN3, PN2, PN1>> ELSE <<PN2, PN3, PN1>>
MCHost(c, t) ==
    LET pref == MCPreference(c.phase)
    IN  IF pref[1] \notin c.out THEN pref[1] ELSE pref[2]

MCOnFailure(c, f) ==
    IF f \in c.out THEN c
    ELSE IF c.out = {} THEN [c EXCEPT !.out = {f}]
    ELSE Safe

MCOnPhase(c) ==
    IF c = Safe THEN {}
    ELSE {[c EXCEPT !.phase = IF @ = "P1" THEN "P2" ELSE "P1"]}

=============================================================================
