------------------------------ MODULE MCOnline ------------------------------
(***************************************************************************)
(* Models of Online: MCOnline.cfg (PN1, the first Master, lies; one        *)
(* crash), MCOnlineObserver.cfg (PN2, the higher-priority Observer, lies;  *)
(* one crash), MCOnlineHonest.cfg (a correct cluster; two crashes), all    *)
(* three in CI; MCOnlineSkip.cfg (bench: MCOnline with the liar's          *)
(* switch numbers up to 2), MCOnlineWire.cfg (bench: MCOnline with every   *)
(* configuration and failed set in the liar's views) and MCOnlineFour.cfg  *)
(* (bench: a correct cluster of four processing nodes and three tasks; two *)
(* crashes).                                                               *)
(*                                                                         *)
(* The paper's prototype: PN1, PN2, PN3 in succession, the Storage node    *)
(* ST1. Two tasks of load 1, each node of capacity 1 (ST1 0): t1,          *)
(* essential and checkpointed, and t2, neither; only PN2 and PN3 are       *)
(* capable of either. The cluster starts with PN1 Master, PN2 and PN3      *)
(* Observers, t1 on PN2 and t2 on PN3. So an online target may keep or     *)
(* swap the two tasks (the double-activation case), shed t2 when one of    *)
(* PN2 and PN3 is out (t1 takes the other), and is SAFE when both are out  *)
(* or ST1 is (t1 is checkpointed): each rule of the checker binds          *)
(* somewhere.                                                              *)
(*                                                                         *)
(*  - MCOnline: PN1 lies as Master of epoch 1 (MaxEpoch 3: its next owned  *)
(*    epoch, 4, is beyond the wire), with switch number 1 only, and one    *)
(*    crash of PN2, PN3 or ST1. PN2 refuses a bad Command and takes over   *)
(*    in epoch 2, with any configuration the checker accepts; PN3 follows  *)
(*    once it refused one too (the exclusion of PN1 is backed); or PN3     *)
(*    takes over in epoch 3 once PN2 crashed. MCOnlineSkip: the same with  *)
(*    switch numbers up to 2 (the liar switches twice, or skips a number). *)
(*  - MCOnlineObserver: PN2 lies, an Observer that owns epoch 2; PN1 is    *)
(*    the correct Master. PN2's Commands of epoch 2 that the checker       *)
(*    accepts are followed (by PN1 too, which steps down), its bad ones    *)
(*    refused: PN1 excludes it on that evidence, or PN3 takes over in      *)
(*    epoch 3.                                                             *)
(*  - MCOnlineHonest: no liar, two crashes (any two nodes: the Master, an  *)
(*    Observer, ST1): PN1, then PN2 or PN3 after a take-over, switches to  *)
(*    whatever configuration the checker accepts at each crash, SAFE only  *)
(*    where none does. MCOnlineFour: the same with PN4 and a third task,   *)
(*    t3, which only PN3 and PN4 are capable of (MCCapableFour), one task  *)
(*    a node: more placements to choose from at each crash, and the        *)
(*    capacity rule binds (t3 moving to PN3 sheds t2 or moves it).         *)
(*                                                                         *)
(* The liar's configurations (MCLiarConfigs): any master (its own, another *)
(* processing node, the Storage node), no observer or one of any node,     *)
(* and any host of each task, a node or Shed; its failed sets none or one  *)
(* node (MCLiarFailedSets). With at most one defect (Online's LiarViews)   *)
(* that is every way to break each rule of the checker alone: a master     *)
(* that is not the view's, failed or not a processing node; an observer    *)
(* missing, failed, the master or not a processing node; a task on a       *)
(* failed, incapable or overloaded node; t1 shed; t1 placed with ST1       *)
(* failed; SAFE where a placement exists. Two observers, which the checker *)
(* takes as it takes one, and two failed nodes (beyond one crash and the   *)
(* liar) are left out. MCOnlineWire.cfg (bench) leaves them in: every      *)
(* configuration and failed set the wire carries (Online's defaults),      *)
(* 6,269 states, no property fails (with PN2 the liar, by hand: 6,978).    *)
(* And the at-most-one-defect rule leaves out no state: by hand, with      *)
(* every view of MCLiarConfigs and MCLiarFailedSets, whatever its defects  *)
(* (LiarCommands <- LiarViews), MCOnline has its 3,777 states.             *)
(***************************************************************************)
EXTENDS Online

CONSTANTS PN1, PN2, PN3, ST1, t1, t2, PN4, t3

MCPriority == <<PN1, PN2, PN3>>
MCCapable == [t \in {t1, t2} |-> {PN2, PN3}]
MCCapacity == [n \in {PN1, PN2, PN3, ST1} |-> IF n = ST1 THEN 0 ELSE 1]
MCLoad == [t \in {t1, t2} |-> 1]
MCInitialConfig ==
    [master |-> PN1, observers |-> {PN2, PN3}, host |-> [t \in {t1, t2} |->
        IF t = t1 THEN PN2 ELSE PN3]]

\* MCOnlineFour: a fourth processing node and a third task, t3, which only PN3 and PN4 are
\* capable of; t1 and t2 may run on PN2, PN3 or PN4, one task a node.
MCPriorityFour == <<PN1, PN2, PN3, PN4>>
MCCapableFour == [t \in {t1, t2, t3} |-> IF t = t3 THEN {PN3, PN4} ELSE {PN2, PN3, PN4}]
MCCapacityFour == [n \in {PN1, PN2, PN3, PN4, ST1} |-> IF n = ST1 THEN 0 ELSE 1]
MCLoadFour == [t \in {t1, t2, t3} |-> 1]
MCInitialConfigFour ==
    [master |-> PN1, observers |-> {PN2},
     host |-> [t \in {t1, t2, t3} |-> CASE t = t1 -> PN2 [] t = t2 -> PN3 [] t = t3 -> PN4]]

MCLiarConfigs ==
    [master : Nodes, observers : {{}} \cup {{x} : x \in Nodes},
     host : [Tasks -> Nodes \cup {Shed}]]
MCLiarFailedSets == {{}} \cup {{x} : x \in Nodes}

(***************************************************************************)
(* Reduction: MCView, the VIEW of the models (as MCValueFault's). States   *)
(* that differ only in messages no step reads again are one state:         *)
(*  - a Command is read only by a node alive whose view is older: a view   *)
(*    is adopted only when newer, and views only grow;                     *)
(*  - a "Prepared" ack of view v is read only by PeersPrepared of a node   *)
(*    alive in v that has not activated it yet, or by a node alive whose   *)
(*    view is older than v, which may adopt v later.                       *)
(* The liar's Commands are constants, not state.                           *)
(***************************************************************************)
MCLiveMsg(msg) == \E n \in Followers \ failed : Newer(msg.view, view[n])
MCLiveAck(a) ==
    \E n \in Followers \ failed :
        \/ view[n] = a.view /\ stage[n] = "Prepared"
        \/ Newer(a.view, view[n])
MCView ==
    <<view, stage, active, declared, failed, {msg \in msgs : MCLiveMsg(msg)},
      {a \in acks : MCLiveAck(a)}>>

(***************************************************************************)
(* Witnesses: each is an invariant TLC must find violated (manifest        *)
(* "witnesses"): the states the properties are about are reachable.        *)
(***************************************************************************)
\* A correct node runs a task that is not on its host in the initial configuration, under a
\* view a correct Master computed online: a task moved and started (the premise of
\* NoDoubleActivationInv). MCOnlineHonest and MCOnline.
WitnessOnlineMoveInv ==
    \A n \in Followers, t \in Tasks :
        ~(t \in active[n] /\ InitialConfig.host[t] # n /\ view[n].master # Liar)
\* A correct node follows an online view that sheds a task (the checker's shedding binds,
\* NoHonestRefusalInv's premise for OnlineNoShedding). MCOnlineHonest.
WitnessOnlineShedInv ==
    \A n \in Followers : ~(view[n].config # Safe /\ Placed(view[n].config) # Tasks)
\* A correct node follows SAFE: no configuration passes the checker. MCOnlineHonest.
WitnessOnlineSafeInv == \A n \in Followers : view[n].config # Safe
\* A correct node refused a Command of the liar's and declared it failed. MCOnline.
WitnessOnlineLiarRefusedInv == \A n \in Followers : Liar \notin declared[n]
\* A correct node follows an online view of the liar's, which passed the checker, and has
\* activated it (the checker does not refuse every lie). MCOnline.
WitnessOnlineLiarFollowedInv ==
    \A n \in Followers : ~(view[n].master = Liar /\ view[n].seq > 0 /\ stage[n] = "Stable")
\* Every correct node alive follows a correct node's take-over, with an online
\* configuration, and runs it (MCOnline: a take-over from the liar, backed).
WitnessOnlineTakeOverInv ==
    ~(\A n \in Followers \ failed :
          /\ view[n].epoch >= 2 /\ view[n].config # Safe /\ stage[n] = "Stable")
\* The first Master, correct, follows the liar's epoch: the liar took over with a Command
\* the checker accepts, of the epoch it owns (MCOnlineObserver).
WitnessOnlineMasterFollowsLiarInv ==
    \A n \in Followers : ~(n = Priority[1] /\ view[n].master = Liar)
\* A correct Master's view excludes the liar, on the evidence of a Command a correct node
\* refused (MCOnlineObserver: the first Master's Exclude, backed by PN3's refusal).
WitnessOnlineLiarExcludedInv ==
    \A m \in Followers : ~(IsMaster(m) /\ view[m].epoch = 1 /\ Liar \in view[m].failed)
\* A correct node follows a view of the liar's, accepted under its own failed set, that
\* places a task on a node that crashed (MCOnline: the liar's view computed as if no node
\* failed). Nothing here is evidence against it: see Online's "Not covered".
WitnessOnlineStaleHostInv ==
    \A n \in Followers :
        ~(/\ view[n].master = Liar /\ view[n].seq > 0 /\ view[n].config # Safe
          /\ stage[n] = "Stable"
          /\ \E t \in Placed(view[n].config) : view[n].config.host[t] \in failed)
=============================================================================
