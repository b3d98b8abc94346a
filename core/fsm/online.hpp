// Online configurations (docs/missions.md, "Placement modes"): beyond the decision graph,
// the Master's placer (core/placement, place.hpp) computes the configuration the cluster
// switches to, the Command carries it whole (View::online), and every node runs the
// checker (core/placement, check.hpp) on it before it acts (spec/Online.tla).
//
// A phase's `placement` says where online configurations may appear:
//   graph         never (the graph's walk, SAFE where it says so);
//   online        every switch of the phase but its initial configuration;
//   graph+online  where the graph's walk ends in SAFE or has no edge, and from there on
//                 until a readmission brings the graph's configuration back.
//
// These are the Master's choices and the receivers' rules, in one place: the
// ReconfigurationManager asks the *_target functions what to switch to, and
// NodeProtocol::command_problem (through admission.hpp) asks online_problem and
// online_edge_problem whether a Command's view is one an honest Master sends. keel-verify
// check proves the same choices by running the same placer (keel-place --prove).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/fsm/topology.hpp"
#include "core/placement/model.hpp"

namespace keel::fsm {

// What a view switches to: a configuration of the graph, SAFE, or an online one
// (`config` kOnlineConfig, `online` set).
struct Target {
    ConfigId config = kSafeConfig;
    OnlinePtr online;

    bool is_safe() const { return config == kSafeConfig; }
    static Target safe() { return Target{}; }
    static Target graph(ConfigId config) { return Target{config, nullptr}; }
};

// The master of a target that is not SAFE.
NodeId master_of(const Topology& topology, const Target& target);

// The configuration `view` runs, in the placer's ids (its base's in safe mode).
placement::Configuration placement_of(const Topology& topology, const View& view);
// The failed set of `failed`, in the placer's form.
placement::FailedSet failed_of(const Topology& topology, const NodeSet& failed);

// The configuration the Master `master` switches to when `fresh` fail (in this order) in
// `from`, the cluster's failed set becoming `failed`: the graph's walk in a graph phase;
// the placer's answer in an online phase, and in a graph+online phase where the walk
// ends in SAFE. SAFE where the answer's master is not `master` (the election made it
// Master: the graph or the placer must agree; kNoNode: any master) or the placer finds
// no placement of the essential tasks. From SAFE, SAFE.
Target failure_target(const Topology& topology, const View& from, const std::vector<NodeId>& fresh,
                      const NodeSet& failed, NodeId master);

// The configuration the cluster returns to when `node` is readmitted while `view` is
// driven (spec/Rejoin.tla): Topology::recovery_target in a graph phase, and in a
// graph+online phase where that is not SAFE and its master is the view's or `node` (a
// hand-over goes to the node that comes back, as in a graph phase); the placer from the
// view's configuration with the smaller failed set otherwise. SAFE when neither places
// the essential tasks.
Target recovery_target(const Topology& topology, const View& view, NodeId node);

// The configuration of `phase` a planned phase change from `from` goes to, or nothing
// (no edge, or no placement): the graph's phase edge (Topology::phase_target) from a
// graph configuration; the phase's recovery target from an online one; each where its
// master is `master`, no failed node is its master or a task's host and, in a phase not
// placed by its graph alone, the checker finds it valid under the failed set; else the
// placer's answer for an online or graph+online phase.
std::optional<Target> phase_target(const Topology& topology, const View& from, PhaseId phase, NodeId master);

// The online configuration of a placement (`config`'s master becomes the view's).
std::shared_ptr<const OnlineConfig> online_of(const Topology& topology, PhaseId phase,
                                              const placement::Configuration& config);

// The receivers' check of an online configuration in `view` (every id of it is the
// mission's: out_of_mission passed): its phase admits online configurations, its master
// is the view's (outside safe mode), and the checker finds it valid under view.failed
// (non-essential tasks may be shed). Why not, or nothing. Safe views check their base.
std::optional<std::string> online_problem(const Topology& topology, const View& view);

// The receivers' check of the next switch of their own view where either end is online
// (same epoch and master, seq + 1; edge_problem's counterpart): a failure switch to any
// online configuration the checker accepts in a phase that admits one, or to SAFE only
// where the placer finds no placement; a phase change to a phase that admits online
// configurations, or to the graph configuration the phase's recovery target names; the
// same configuration again. Why not, or nothing.
std::optional<std::string> online_edge_problem(const Topology& topology, const View& from, const View& next);

// The nodes the next switch `next` of a view `from` excludes beyond it (a failure switch
// keeps every exclusion and adds some), in id order, into `fresh`; or why no honest
// Master's next switch does so (it readmits a node: a readmission opens an epoch; or it
// excludes more than a few at once). admission.hpp's edge_problem and online_edge_problem
// share it.
std::optional<std::string> fresh_exclusions(const View& from, const View& next, std::vector<NodeId>* fresh);

// A compact description of an online configuration for traces and logs:
// {"phase":P,"m":M,"obs":[...],"host":{task:node,...}} (shed tasks are absent).
std::string online_json(const Topology& topology, const OnlineConfig& online);

}  // namespace keel::fsm
