// ReconfigurationManager: the Master's decisions (the paper's reconfiguration manager;
// the Exclude, RequestPhase and BecomeMaster actions of spec/ConfigSwitch.tla).
//
// It holds the configuration the Master drives (masterConfig), the nodes it has declared
// failed and the Master's switch counter (masterSeq), and answers one question: given a
// detected failure, a phase request or a take-over, which view should the cluster switch
// to next? It walks the mission's decision graph (Topology::walk) from the configuration
// being driven — the target of the switch under way, if any, as the spec says — and
// answers SAFE when no edge applies; in a phase placed online, the placer answers where
// the mission says so (online.hpp). It never sends: ConfigSwitch carries the view out.
//
// Ordering contract:
//  1. Only the node whose Election role is Master calls exclude() and on_phase();
//     take_over() is called right after Election::become_master(); step_down() whenever
//     the Election role stops being Master.
//  2. Every view returned must be handed to ConfigSwitch::start_switch() before the next
//     event, since masterSeq has already advanced.
//  3. A failure of a node already excluded, or a phase request in safe mode or without an
//     edge, returns nothing and changes nothing.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/fsm/actions.hpp"
#include "core/fsm/mutants.hpp"
#include "core/fsm/online.hpp"
#include "core/fsm/topology.hpp"

namespace keel::fsm {

class JsonObject;

// Why the Master excludes a node, logged with its Exclude line and checked there by
// trace validation (spec/trace/TraceConfigSwitch.tla, EvidenceSuffices; spec/Quorum.tla,
// rule 1): the node's own word (it restarted, resigned, or says it is excluded), or the
// members of the driving view and the declarations among them that counted.
struct Evidence {
    bool own = false;
    NodeSet members;
    NodeSet declared;
    // The ground holds the node out (docs/operations.md, `exclude`): the Master's own walk
    // of the graph from its view passed (NodeProtocol::exclude_held_out).
    bool ground = false;
    // spec/Designate.tla (a mission with heartbeat.tie_grace): the ground is a member of the
    // view decided in (`gm`: an even number of monitors there), and the ground's vote
    // completed the declarations (`vote`: the decider holds it).
    bool gm = false;
    bool vote = false;

    static Evidence own_word() { return Evidence{true, {}, {}}; }
    static Evidence ground_hold() {
        Evidence evidence;
        evidence.ground = true;
        return evidence;
    }
};

// Why a node that takes over excludes each node it excludes (traced with its BecomeMaster
// line, checked by TraceConfigSwitch's TakeOverEvidence): the members of the view it takes
// over, and per node the declarations that counted; a node without an entry is excluded
// on its own word.
struct TakeOverEvidence {
    NodeSet members;
    std::vector<std::pair<NodeId, NodeSet>> declared;
    NodeSet passed;  // the members passed over (NodeProtocol::diverged): no members, no voters
    NodeSet newer;   // of them, those whose Prepared named a newer switch of the view's epoch
    NodeSet unprepared;  // and those whose Prepared of the view never reached the taker
    // spec/Designate.tla: the ground a member of the view taken over, and the nodes whose
    // exclusion the ground's vote completed.
    bool gm = false;
    NodeSet voted;
};

class ReconfigurationManager {
public:
    ReconfigurationManager(const Topology& topology, NodeId self, Mutant mutant);

    bool active() const { return active_; }
    const View& driving() const { return driving_; }  // masterConfig, failed, masterSeq

    // The initial Master at first boot drives the initial view (seq 0, nothing active yet).
    void boot_as_master(const View& initial);
    // The boot switch: the initial configuration again, at seq 1, nobody failed. Its two
    // phases are what activates the initial tasks on every node (NodeProtocol's contract).
    View boot_switch(Outbox& out);
    // BecomeMaster: continue from `view` (the last view this node accepted) in `epoch`,
    // excluding `suspects`. Always returns the view to switch to.
    // WarmBoot (spec/MasterElection.tla): after a whole-cluster power cycle this node, the
    // master of its phase's initial configuration `target`, drives `target` in `epoch`
    // with no node failed; returns the view of its first switch (seq 1). Traced as the
    // switch's BecomeMaster (a take-over that excludes no one).
    View warm_boot(Epoch epoch, ConfigId target, Outbox& out);
    View take_over(const View& view, Epoch epoch, NodeSet suspects, const TakeOverEvidence& evidence,
                   Outbox& out);
    // BecomeMaster again in `epoch` (Election::reclaim): the driven view, re-announced.
    View reclaim(Epoch epoch, Outbox& out);
    // Exclude(m, f) at the Master, on `evidence` (traced with the line).
    std::optional<View> exclude(NodeId failed, const Evidence& evidence, Outbox& out);
    // RequestPhase(m, c).
    std::optional<View> on_phase(PhaseId phase, Outbox& out);
    // Reintegration (spec/Rejoin.tla): `node` is readmitted and the cluster returns to
    // `target` (online.hpp's recovery_target), whose master is this node, in this node's
    // next epoch; safe mode is left this way too. Traced as Readmit.
    View readmit(NodeId node, const Target& target, Outbox& out);
    // The same when `target`'s master is another node: the view this Master hands over
    // (that node's next epoch, seq 0), which it adopts itself and stops driving. Traced
    // as HandOver.
    View hand_over(NodeId node, const Target& target, Outbox& out);
    // A ground command in safe mode (fault model 2, item 3): leave SAFE for `target`, a
    // configuration of the phase safe mode was entered in, whose master is this node and
    // which places nothing (its master, observers or tasks) on a node the cluster has
    // excluded. Every configuration of the mission is one `keel-verify check` proved;
    // the failed set is kept, so its failure edges still apply. Returns the view, or
    // nothing with `why` saying which condition failed. Traced as GroundRecovery.
    std::optional<View> ground_recovery(ConfigId target, std::string* why, Outbox& out);
    void step_down() { active_ = false; }

private:
    View next_view(const Target& target, NodeSet failed) const;
    // The trace's "c" (and "online", for an online target) of `target`.
    void target_fields(JsonObject& args, const Target& target) const;
    void trace(const char* action, std::string args, Outbox& out) const;

    const Topology* topology_;
    NodeId self_;
    Mutant mutant_;
    bool active_ = false;
    View driving_;
};

}  // namespace keel::fsm
