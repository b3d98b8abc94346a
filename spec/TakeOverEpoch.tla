---------------------------- MODULE TakeOverEpoch ----------------------------
(***************************************************************************)
(* The take-over's epoch against a liar (docs/fault-model.md, "A           *)
(* value-faulty node in the simulator": keel-sim --liar, prototype3 seed   *)
(* 49016). The module extends ElectionLiar: its nodes, epochs and their    *)
(* owners, the liar, which while it runs its first boot takes no step of   *)
(* the protocol and forges Commands of an epoch of its own, each to one    *)
(* node alone (ForgeCommand; no hand-over here), its crash, which ends its *)
(* lies, rule (2) (SuspectLeft), the runtime's guard of the take-over      *)
(* (DeclaredGone) and Reclaim. It adds the lease's acknowledgement rule    *)
(* and a take-over that opens above the epoch its voters follow.           *)
(*                                                                         *)
(* The lease (NodeProtocol::enforce_lease, holds_lease, resign;            *)
(* docs/fault-model.md, the lease): a voter of a newer epoch acknowledges  *)
(* no Master of an older one. A Master whose running voter follows a newer *)
(* epoch steps down (LeaseStepDown, counted lease_step_downs). The spec    *)
(* abstracts the count to any such voter: once the liar has crashed two    *)
(* nodes run, the Master's one voter is all its lease rests on (one        *)
(* declaration suffices when one voter is left), and the abstraction is    *)
(* the runtime's rule; with three running it steps down earlier than the   *)
(* runtime would, which only makes liveness harder. The step-down is for   *)
(* good: the node commands no more and says it is out (MasterElection's    *)
(* fenced: it claims no epoch until a Master readmits it). Its word        *)
(* carries its epoch, and a node of a newer epoch takes it as stale: a     *)
(* node declares it on that word only when its own epoch is not newer      *)
(* (HearStepDown, MasterElection's SuspectFenced so guarded; seed 49016:   *)
(* PN2's word of epoch 5 was never news to PN3, which followed epoch 7).   *)
(*                                                                         *)
(* The rule (NodeProtocol::take_over, its `above`; unit test               *)
(* ATakeOverOpensAnEpochAboveOneItsVotersFollowOfTheNodeItSucceeds): a     *)
(* take-over opens the first epoch its taker owns above the highest epoch  *)
(* a voter acknowledges whose owner is a node the take-over replaces       *)
(* (VoterEpoch), when that is above ElectionLiar's floor (TakeOverFloor:   *)
(* the taker's epoch, or the one a Master it declared left follows). A     *)
(* heartbeat says the highest epoch its sender adopted. The voters: the    *)
(* monitors of the taker's view (here every processing node) but the taker *)
(* and the nodes it replaces, those that run. The nodes it replaces        *)
(* (Replaced): the Master of its view and the Observers ahead of it in the *)
(* succession, each declared by the taker or restarted since its epoch was *)
(* opened. An epoch of a node it does not replace (one behind it, a Master *)
(* it missed) is that node's, and no take-over moves past it. The voter    *)
(* adopts the new epoch, a Command of a newer epoch from its owner         *)
(* (MasterElection's ReceiveCommand), and the new Master holds its lease.  *)
(* Without the rule the take-over opens below the voter's epoch and its    *)
(* lease lapses at once, before Reclaim (NodeProtocol::tick's              *)
(* newer_epoch_, after MissLimit periods) moves it past that epoch: the    *)
(* spec has no time, both steps are enabled, and a behaviour takes the     *)
(* step-down first. The take-over's epoch is a parameter of TakeOverBy, so *)
(* that the mutant passes the floor before the rule.                       *)
(*                                                                         *)
(* Properties (the correct nodes are Nodes \ {Liar}):                      *)
(*  - MasterElection's OneMasterPerEpochInv, MasterOwnsEpochInv,           *)
(*    NoStaleMastershipInv, EpochMonotoneProp, StaleCommandRejectedProp.   *)
(*  - TakeOverLiveness: under fairness (ElectionLiar's, with the step-down *)
(*    fair too: a lease that lapses lapses), once the liar has crashed,    *)
(*    eventually, for good, a running Master holds its lease with every    *)
(*    running node following it in its epoch (LeaseHeld).                  *)
(*                                                                         *)
(* What TLC shows (MCTakeOverEpoch.tla has the model; one worker): PN1,    *)
(* the first Master, lies once, sending PN2 or PN3 alone a Command of an   *)
(* epoch of its own within a lap, and crashes for good; no false           *)
(* declaration.                                                            *)
(*  - MCTakeOverEpoch: 67 states, no violation; no Master ever steps down  *)
(*    (by hand, an invariant that no node is fenced holds on the 67        *)
(*    states).                                                             *)
(*  - Without the rule (TakeOverOwnEpochOnly) TLC finds seed 49016 on      *)
(*    three nodes (71 states): PN1 sends PN3 alone its epoch 4 and         *)
(*    crashes; PN2 takes over epoch 2, PN3's acknowledgements of epoch 4   *)
(*    do not count for it, and it steps down at once; its word is of epoch *)
(*    2, stale for PN3, which waits for PN2, the owner of epoch 5, ahead   *)
(*    of it in the succession of epoch 4: no Master ever again.            *)
(*  - WitnessTakeOverAboveVoterInv: PN3 follows PN1's epoch 4, PN1         *)
(*    crashes, PN2 takes over epoch 5, PN3 adopts it, and PN2 holds its    *)
(*    lease.                                                               *)
(*  - By hand: the mutant holds when a step-down is heard at any epoch (76 *)
(*    states): the rule is needed because the word of a Master that steps  *)
(*    down is stale for a voter ahead of it. The rule reading every        *)
(*    voter's epoch, whoever its owner, holds too (67 states): here no     *)
(*    voter follows an epoch of a node the taker does not replace (that    *)
(*    needs a Master the taker missed), so the owner clause binds nothing  *)
(*    in this model.                                                       *)
(*                                                                         *)
(* Not covered (stated, not hidden): a lie that reaches a voter after the  *)
(* take-over. With two lies (316 states) or one false declaration (481     *)
(* states) TLC finds TakeOverLiveness violated, each time so: PN2 takes    *)
(* over while PN1 still runs (it declared PN1 left, or declared it         *)
(* falsely), the liar then moves PN3 to an epoch of its own above PN2's    *)
(* new one, and PN2 steps down at once: no take-over rule moves past an    *)
(* epoch no voter follows yet, and Reclaim comes after the lease has       *)
(* lapsed. Whether the runtime's receiver checks or its evidence for a     *)
(* take-over (two monitors' declarations, where here one node's suffices)  *)
(* rule these out is not shown here. The adoptable bound (an epoch at most *)
(* a lap, growing a lap a period, above what the taker knows): with one    *)
(* lie a voter's epoch is within a lap of the taker's, so the bound never  *)
(* binds, and a take-over beyond it is EpochBound's (OpenOk). A node that  *)
(* knows no epoch (no Command since it booted): no restarts here.          *)
(* Evidence: a node the taker replaces is one it declared, where the       *)
(* runtime needs a majority of the monitors' declarations (Exclusion.tla); *)
(* a node merely suspected is not told apart. Honest hand-overs, fences    *)
(* and the liar's hand-overs are ElectionLiar's models'.                   *)
(***************************************************************************)
EXTENDS ElectionLiar

VARIABLES
    aboveVoter  \* history: a take-over opened above the epoch of a voter (VoterEpoch)

takeOverVars == <<allVars, aboveVoter>>

TInit == LInit /\ aboveVoter = FALSE

(***************************************************************************)
(* The take-over's epoch                                                   *)
(***************************************************************************)

\* The nodes a take-over by n replaces: the Master of n's view (the owner of its epoch) and
\* the Observers ahead of n in the succession, each declared by n (its silence, its word
\* that it stepped down or left) or restarted since n's epoch was opened (its own word).
\* The take-over's guard (DeclaredGone, Ahead(n) \subseteq suspects[n]) holds them all so.
Replaced(n) ==
    {m \in ({Owner(epoch[n])} \cup Ahead(n)) \ {n} :
        m \in suspects[n] \/ restartEpoch[m] >= epoch[n]}

\* n's voters: the monitors of its view (here every processing node) but n and the nodes it
\* replaces, those that run (a crashed one acknowledges nothing).
Voters(n) == {v \in Nodes \ ({n} \cup Replaced(n)) : alive[v]}

\* The highest epoch a voter of n's acknowledges (a heartbeat says the highest epoch its
\* sender adopted) whose owner is a node n replaces; 0 for none. An epoch of a node n does
\* not replace (one behind it, a Master n missed) is that node's, and not moved past.
VoterEpoch(n) ==
    MaxEpochOf({epoch[v] : v \in {x \in Voters(n) :
                                     epoch[x] >= 1 /\ Owner(epoch[x]) \in Replaced(n)}})

\* The epoch above which n takes over (NodeProtocol::take_over): ElectionLiar's floor (n's
\* epoch, or the one a Master n declared left follows), or the voters' epoch when higher.
VoterFloor(n) ==
    IF VoterEpoch(n) > TakeOverFloor(n) THEN VoterEpoch(n) ELSE TakeOverFloor(n)

\* ElectionLiar's take-over (LBecomeMaster, its guard the runtime's) opening the first epoch
\* n owns above Floor(n), a parameter so that a mutant passes the rule before.
TakeOverBy(Floor(_), n) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] # "Master"
    /\ ~Waiting(n)
    /\ ~fenced[n]
    /\ DeclaredGone(n)
    /\ Ahead(n) \subseteq suspects[n]
    /\ LET e == NextEpochAbove(n, Floor(n)) IN
        /\ epoch' = [epoch EXCEPT ![n] = e]
        /\ role' = [role EXCEPT ![n] = "Master"]
        /\ leader' = [leader EXCEPT ![n] = n]
        /\ lastCommand' = [lastCommand EXCEPT ![n] = e]
        /\ msgs' = msgs \cup {[epoch |-> e, from |-> n]}
    /\ aboveVoter' = (aboveVoter \/ Floor(n) > TakeOverFloor(n))
    /\ UNCHANGED <<alive, suspects, handOvers, boot, restartEpoch, crashes, restarts,
                   falseSuspicions, handOverCount, fenced, fenceCount>>
    /\ UNCHANGED liarVars

TakeOver(n) == TakeOverBy(VoterFloor, n)

(***************************************************************************)
(* The lease                                                               *)
(***************************************************************************)

\* A Master whose running voter follows a newer epoch steps down for good (NodeProtocol::
\* enforce_lease, resign; counted lease_step_downs): such a voter acknowledges no Master of
\* an older epoch. It stops commanding, and says it is out (fenced: it claims no epoch
\* until a Master readmits it).
LeaseStepDown(n) ==
    /\ Acts(n)
    /\ alive[n]
    /\ role[n] = "Master"
    /\ \E v \in Nodes \ {n} : alive[v] /\ epoch[v] > epoch[n]
    /\ role' = [role EXCEPT ![n] = "Worker"]
    /\ fenced' = [fenced EXCEPT ![n] = TRUE]
    /\ UNCHANGED <<alive, epoch, leader, suspects, lastCommand, msgs, handOvers, boot,
                   restartEpoch, crashes, restarts, falseSuspicions, handOverCount,
                   fenceCount>>
    /\ UNCHANGED liarVars
    /\ UNCHANGED aboveVoter

\* n takes m's word that it stepped down (MasterElection's SuspectFenced) only when m's
\* epoch is not older than n's: the word carries m's epoch, no news to a node of a newer one
\* (seed 49016: PN2's word of epoch 5 never reached PN3, at epoch 7, as news).
HearStepDown(n, m) == LSuspectFenced(n, m) /\ epoch[m] >= epoch[n] /\ UNCHANGED aboveVoter

(***************************************************************************)
(* Next state and fairness                                                 *)
(***************************************************************************)

\* MasterElection's and ElectionLiar's other steps, by a node that does not lie, leaving the
\* history alone.
TSuspect(n, m) == LSuspect(n, m) /\ UNCHANGED aboveVoter
TSuspectLeft(n, m) == SuspectLeft(n, m) /\ UNCHANGED aboveVoter
TReclaim(n, above) == Reclaim(n, above) /\ UNCHANGED aboveVoter
TWarmBoot(n) == LWarmBoot(n) /\ UNCHANGED aboveVoter
TBroadcastCommand(n) == LBroadcastCommand(n) /\ UNCHANGED aboveVoter
TReceiveCommand(n, msg) == LReceiveCommand(n, msg) /\ UNCHANGED aboveVoter
TReadmit(m, n) == LReadmit(m, n) /\ UNCHANGED aboveVoter
TReceiveForged(x, c) == ReceiveForged(x, c) /\ UNCHANGED aboveVoter

\* The liar's lie: a Command of an epoch of its own to one node (no hand-over).
TForgeCommand(x, e) == ForgeCommand(x, e) /\ UNCHANGED aboveVoter

\* The one crash is the liar's, which ends its lies; it does not restart (MaxRestarts = 0).
TCrash(n) == n = Liar /\ LCrash(n) /\ UNCHANGED aboveVoter

\* Every step but the take-over, which TNext and a mutant's next-state relation add.
TNextBut ==
    \/ \E n \in Nodes : LeaseStepDown(n)
    \/ \E n, m \in Nodes : HearStepDown(n, m)
    \/ \E n, m \in Nodes : TSuspect(n, m)
    \/ \E n, m \in Nodes : TSuspectLeft(n, m)
    \/ \E n \in Nodes, e \in {epoch[x] : x \in Nodes} : TReclaim(n, e)
    \/ \E n \in Nodes : TWarmBoot(n)
    \/ \E n \in Nodes : TBroadcastCommand(n)
    \/ \E n \in Nodes, msg \in msgs : TReceiveCommand(n, msg)
    \/ \E m, n \in Nodes : TReadmit(m, n)
    \/ \E x \in Nodes, c \in forged : TReceiveForged(x, c)
    \/ \E x \in Nodes, e \in ForgeableEpochs : TForgeCommand(x, e)
    \/ \E n \in Nodes : TCrash(n)

\* MasterElection's fairness (ElectionLiar's LFairness) and the step-down's (a lease that
\* lapses lapses), all but the take-over's, which TFairSpec and a mutant's spec add. The
\* liar's message need not arrive.
TFairnessBut ==
    /\ \A n, m \in Nodes : WF_takeOverVars(~alive[m] /\ TSuspect(n, m))
    /\ \A n, m \in Nodes : WF_takeOverVars(HearStepDown(n, m))
    /\ \A n, m \in Nodes : WF_takeOverVars(TSuspectLeft(n, m))
    /\ \A n \in Nodes : WF_takeOverVars(LeaseStepDown(n))
    /\ \A n \in Nodes : WF_takeOverVars(\E e \in {epoch[x] : x \in Nodes} : TReclaim(n, e))
    /\ WF_takeOverVars(\E n \in Nodes : TWarmBoot(n))
    /\ \A n \in Nodes : WF_takeOverVars(TBroadcastCommand(n))
    /\ \A n \in Nodes : WF_takeOverVars(\E msg \in msgs : TReceiveCommand(n, msg))

TNext == TNextBut \/ \E n \in Nodes : TakeOver(n)
TSpec == TInit /\ [][TNext]_takeOverVars
TFairSpec == TSpec /\ TFairnessBut /\ \A n \in Nodes : WF_takeOverVars(TakeOver(n))

(***************************************************************************)
(* Properties                                                              *)
(***************************************************************************)

\* A running Master that every running node follows in its epoch: its lease holds (no
\* running voter follows a newer epoch), so it does not step down.
LeaseHeld ==
    \E m \in Nodes :
        /\ alive[m]
        /\ role[m] = "Master"
        /\ \A x \in Nodes : alive[x] => leader[x] = m /\ epoch[x] = epoch[m]

\* Once the liar has crashed, eventually, for good, a running Master holds its lease with
\* every running node following it.
TakeOverLiveness == <>~lying => <>[]LeaseHeld

=============================================================================
