----------------------------- MODULE MCHeartbeat -----------------------------
(***************************************************************************)
(* Model of Heartbeat for CI: the paper's prototype, processing nodes PN1  *)
(* (the Master), PN2, PN3 (the Observers) and the Storage node ST1.        *)
(*                                                                         *)
(* Monitors = {PN1, PN2}: the monitors share no protocol state (each keeps *)
(* its own heard, missed and failed, and the properties are conjunctions   *)
(* over monitors), so a second monitor adds the cases a third would (a     *)
(* monitor watched by a monitor, a monitor that crashes) while a third     *)
(* would multiply the state space by the outcomes of its three links.      *)
(* MissLimit = 2 separates "one heartbeat lost" from "declared failed";    *)
(* MaxLoss = MissLimit - 1 is the largest loss the accuracy property       *)
(* covers; one crash shows completeness. The monitors are interchangeable, *)
(* and so are the watched-only nodes (PN3, ST1): two symmetry sets (there  *)
(* is no liveness property for symmetry to be unsound for).               *)
(*                                                                         *)
(* Reduction. Sends, receipts and losses within one period touch one link  *)
(* each and commute with one another; the properties read only alive,      *)
(* failed, missed and downFor, which change only at Tick, DeclareFailed    *)
(* and Crash. So checking the behaviours where one node's heartbeats are   *)
(* on the wire at a time (MCOneSenderAtATime, an action constraint) covers *)
(* every reachable value of those variables, at a fraction of the states.  *)
(* The spec itself keeps every interleaving, for trace validation.        *)
(***************************************************************************)
EXTENDS Heartbeat, TLC

MCSymmetry == Permutations(Monitors) \cup Permutations(Nodes \ Monitors)

\* A node sends only when the previous node's heartbeats have all arrived or been lost.
MCOneSenderAtATime ==
    (\E n \in Nodes : ~sent[n] /\ sent'[n]) => inFlight = {}

\* For mission-sized models: at most MCMaxLossyLinks links are in a loss streak at once.
\* This bounds the environment (losses on many links at once are not explored); it is
\* not a reduction, and the CI model sets it to the number of links (no bound).
CONSTANT MCMaxLossyLinks

\* Reduction (the VIEW of the models): when StartupGrace = MissLimit, heardOnce changes
\* nothing: DeclareAt, DownForCap and CompletenessInv pick between two equal bounds. So
\* states that differ only in heardOnce have the same steps, to states that again differ
\* only in it (a bisimulation), and the view leaves it out; with a longer grace it is
\* the whole state.
MCView ==
    IF StartupGrace = MissLimit
    THEN <<alive, sent, inFlight, lossRun, heard, missed, failed, downFor, unbooted,
           clock>>
    ELSE vars
MCLossyLinks == {<<m, n>> \in Monitors \X Nodes : lossRun[m][n] > 0}
MCLossConstraint == Cardinality(MCLossyLinks) <= MCMaxLossyLinks
=============================================================================
