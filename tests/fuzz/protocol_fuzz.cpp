// The protocol fuzzer (fault model 3, docs/fault-model.md): libFuzzer drives fsm::decode and
// NodeProtocol with arbitrary message sequences, from every role and stage, on both shipped
// missions (and the earth-observation mission placed graph+online, where Commands carry the
// placer's configurations), and checks the invariants of invariants.hpp after every call (README.md: how
// to build, run and replay it).
//
// An input, read with FuzzedDataProvider (which takes integers from the input's end and
// byte strings from its front):
//   byte 0       bits 0 and 2 the mission (0 prototype3, 1 earth-observation, 2 and 3
//                earth-observation placed graph+online), bit 1 whether the nodes build
//                their trace lines (as with keel-node's --trace)
//   two integers an honest prefix (prefix.hpp): a scenario, and how many heartbeat periods
//                of it ran; the cluster starts from that copy
//   then up to kMaxRecords records, each an operation and its arguments:
//     forge        receiver, time advance (ms), bytes (length first): fsm::decode; if they
//                  decode, the receiver steps the message (unless it names the receiver as
//                  its sender: the runtime drops those)
//     forge_typed  receiver, time advance, a message kind and its fields, drawn near the
//                  receiver's own epoch, switch and versions (ids may be one beyond the
//                  mission's), through the codec and stepped as above
//     tamper       a message in flight, encoded, with up to four bytes overwritten, to its
//                  receiver or another (the honest copy stays in flight)
//     deliver      a message in flight, now, out of order
//     drop         a message in flight, lost
//     replay       a message delivered lately, again, to its receiver or another
//     advance      the honest network and every node's boundaries, up to two periods
//     stall        the clock jumps up to eight periods: every node's loop ran late
//     tick, task_stepped, request_phase, request_recovery, resign, crash, restart
//                  of a node, now
// Every advance of the clock runs the honest network, so the nodes' reactions to what was
// forged go on; an input covers at most kMaxRunNs of time.
//
// The whole input is also handed to fsm::decode as one message, and whatever decodes must
// encode to the same bytes (CodecRoundTripInv).
//
// KEEL_FUZZ_MUTANT (the test build keel-protocol-fuzz-mutant only): every node runs that
// mutant of core/fsm/mutants.hpp, which the fuzzer must catch (CMakeLists.txt).
#include <fuzzer/FuzzedDataProvider.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "core/fsm/codec.hpp"
#include "core/mission/image.hpp"
#include "tests/fuzz/cluster.hpp"
#include "tests/fuzz/prefix.hpp"

namespace keel::fuzz {
namespace {

inline constexpr int kMaxRecords = 64;
inline constexpr std::size_t kMaxForgedBytes = 512;
inline constexpr std::size_t kMaxStateBytes = 64;
inline constexpr TimeNs kMillisecond = fsm::kNanosecondsPerMillisecond;
inline constexpr TimeNs kMaxRunNs = 1'500 * kMillisecond;

struct Mission {
    explicit Mission(fsm::Topology compiled)
        : topology(std::move(compiled)),
          prefixes{Prefixes(topology, false), Prefixes(topology, true)} {}
    fsm::Topology topology;
    std::array<Prefixes, 2> prefixes;  // the nodes' tracing off, on
};

// The shipped missions, as nodes fly them: their compiled images, which
// tests/missions/test_images.py keeps current with config/*.yaml.
constexpr std::array<const char*, 3> kMissionImages{"prototype3.json", "earth_observation.json",
                                                    "earth_observation_online.json"};
std::array<std::unique_ptr<Mission>, 3> missions;

std::unique_ptr<Mission> load(const std::string& folder, const char* file) {
    const std::string path = folder + "/" + file;
    const auto loaded = mission::load_mission_image(path);
    if (!loaded.ok()) {
        std::fprintf(stderr, "keel-protocol-fuzz: %s: %s\n", path.c_str(),
                     loaded.errors.empty() ? "not loaded" : loaded.errors[0].to_string().c_str());
        std::exit(2);
    }
    std::string error;
    auto topology = fsm::Topology::build(*loaded.mission, &error);
    if (!topology) {
        std::fprintf(stderr, "keel-protocol-fuzz: %s: %s\n", path.c_str(), error.c_str());
        std::exit(2);
    }
    return std::make_unique<Mission>(std::move(*topology));
}

enum class Op : std::uint8_t {
    forge,
    forge_typed,
    tamper,
    deliver,
    drop,
    replay,
    advance,
    stall,
    tick,
    task_stepped,
    request_phase,
    request_recovery,
    resign,
    crash,
    restart,
};
inline constexpr int kOps = static_cast<int>(Op::restart) + 1;

// The operations of one input on one cluster.
class Run {
  public:
    Run(Cluster& cluster, FuzzedDataProvider& input) : cluster_(cluster), input_(input) {}

    void record() {
        const auto op = static_cast<Op>(input_.ConsumeIntegralInRange<int>(0, kOps - 1));
        switch (op) {
            case Op::forge:
                forge();
                break;
            case Op::forge_typed:
                forge_typed();
                break;
            case Op::tamper:
                tamper();
                break;
            case Op::deliver:
                if (!cluster_.in_flight().empty()) {
                    cluster_.deliver_in_flight(index(cluster_.in_flight().size()));
                }
                break;
            case Op::drop:
                if (!cluster_.in_flight().empty()) {
                    cluster_.drop_in_flight(index(cluster_.in_flight().size()));
                }
                break;
            case Op::replay:
                replay();
                break;
            case Op::advance:
                advance(2 * period());
                break;
            case Op::stall:
                cluster_.stall(
                    input_.ConsumeIntegralInRange<TimeNs>(0, 8 * period() / kMillisecond) *
                    kMillisecond);
                break;
            case Op::tick:
                cluster_.tick(node());
                break;
            case Op::task_stepped:
                task_stepped();
                break;
            case Op::request_phase: {
                const NodeId to = node();
                cluster_.request_phase(to, input_.ConsumeIntegral<fsm::PhaseId>());
                break;
            }
            case Op::request_recovery: {
                const NodeId to = node();
                cluster_.request_recovery(to, config());
                break;
            }
            case Op::resign:
                cluster_.resign(node());
                break;
            case Op::crash:
                cluster_.crash(node());
                break;
            case Op::restart:
                cluster_.restart(node());
                break;
        }
    }

  private:
    const fsm::Topology& topology() const { return cluster_.topology(); }
    TimeNs period() const { return topology().heartbeat_period_ns(); }
    NodeId node() {
        return input_.ConsumeIntegralInRange<NodeId>(
            0, static_cast<NodeId>(cluster_.node_count() - 1));
    }
    // One byte, whatever the size (a seed's bytes keep their meaning as the queues change).
    std::size_t index(std::size_t size) { return input_.ConsumeIntegral<std::uint8_t>() % size; }
    void advance(TimeNs most) {
        const TimeNs step =
            input_.ConsumeIntegralInRange<TimeNs>(0, most / kMillisecond) * kMillisecond;
        cluster_.run_until(cluster_.now() + step);
    }

    // Bytes the receiver's runtime would hand to decode, then to the node.
    void deliver_bytes(NodeId to, std::span<const std::uint8_t> bytes) {
        const fsm::DecodedMessage decoded = fsm::decode(bytes);
        Invariants::check_decoded(bytes, decoded);
        if (decoded.ok()) cluster_.step(to, *decoded.message);
    }

    void forge() {
        const NodeId to = node();
        advance(period());
        const auto length = input_.ConsumeIntegralInRange<std::size_t>(0, kMaxForgedBytes);
        const std::vector<std::uint8_t> bytes = input_.ConsumeBytes<std::uint8_t>(length);
        deliver_bytes(to, bytes);
    }

    void forge_typed() {
        const NodeId to = node();
        advance(period());
        if (!cluster_.up(to)) return;
        const fsm::Message message = typed(cluster_.node(to));
        deliver_bytes(to, fsm::encode(message));
    }

    void tamper() {
        if (cluster_.in_flight().empty()) return;
        const InFlight& original = cluster_.in_flight()[index(cluster_.in_flight().size())];
        const NodeId to = input_.ConsumeBool() ? original.to : node();
        std::vector<std::uint8_t> bytes = fsm::encode(original.message);
        const int edits = input_.ConsumeIntegralInRange<int>(1, 4);
        for (int edit = 0; edit < edits; ++edit) {
            bytes[index(bytes.size())] = input_.ConsumeIntegral<std::uint8_t>();
        }
        deliver_bytes(to, bytes);
    }

    void replay() {
        if (cluster_.delivered().empty()) return;
        const InFlight copy = cluster_.delivered()[index(cluster_.delivered().size())];
        const NodeId to = input_.ConsumeBool() ? copy.to : node();
        cluster_.step(to, copy.message);
    }

    void task_stepped() {
        const NodeId at = node();
        if (!cluster_.up(at) || cluster_.running(at).empty()) return;
        std::vector<TaskId> running;
        cluster_.running(at).for_each([&](TaskId task) { running.push_back(task); });
        const TaskId task = running[index(running.size())];
        // A component's state stays within the mission's bound (the runtime drops a larger one).
        std::size_t most = kMaxStateBytes;
        if (const auto bound = topology().task(task).max_state_bytes) most = std::min(most, *bound);
        const auto length = input_.ConsumeIntegralInRange<std::size_t>(0, most);
        cluster_.task_stepped(at, task, input_.ConsumeBytes<std::uint8_t>(length));
    }

    // --- fields of a typed message, near the receiver's own values ---
    // Mostly a few steps from `base`, sometimes anywhere within the wire's width.
    std::uint32_t near(std::uint32_t base, std::uint32_t width_max) {
        const auto choice = input_.ConsumeIntegral<std::uint8_t>();
        if (choice >= 240) return input_.ConsumeIntegralInRange<std::uint32_t>(0, width_max);
        const std::int64_t value = std::int64_t{base} + (choice % 12) - 3;
        return static_cast<std::uint32_t>(std::clamp<std::int64_t>(value, 0, width_max));
    }
    // A node id of the mission, or one beyond it.
    NodeId any_node() {
        return input_.ConsumeIntegralInRange<NodeId>(0, static_cast<NodeId>(cluster_.node_count()));
    }
    TaskId task() {
        return input_.ConsumeIntegralInRange<TaskId>(0,
                                                     static_cast<TaskId>(topology().task_count()));
    }
    // A configuration of the mission, safe mode, or one beyond.
    fsm::ConfigId config() {
        const auto count = static_cast<fsm::ConfigId>(topology().config_count());
        const auto id = input_.ConsumeIntegralInRange<fsm::ConfigId>(0, count + 1);
        return id == count + 1 ? fsm::kSafeConfig : id;
    }
    fsm::NodeSet node_set() {
        fsm::NodeSet set;
        const auto bits = input_.ConsumeIntegral<std::uint16_t>();
        for (int n = 0; n <= cluster_.node_count() && n < 16; ++n) {
            if ((bits >> n) & 1u) set.insert(static_cast<NodeId>(n));
        }
        return set;
    }
    fsm::View view(const fsm::View& around) {
        fsm::View view;
        view.epoch = near(around.epoch, fsm::kMaxEpoch);
        view.seq = near(around.seq, fsm::kMaxSeq);
        view.config = config();
        view.base = input_.ConsumeBool() ? view.config : config();
        view.master =
            input_.ConsumeBool() ? topology().owner(view.epoch == 0 ? 1 : view.epoch) : any_node();
        view.failed = input_.ConsumeBool() ? around.failed | node_set() : node_set();
        return view;
    }
    fsm::Version version(const fsm::NodeProtocol& at, TaskId task, fsm::Epoch epoch) {
        fsm::Version base;
        if (static_cast<int>(task) < topology().task_count()) {
            base = at.config_switch().version(task);
        }
        fsm::Version version;
        if (input_.ConsumeBool()) {
            version.lineage = base.lineage;
        } else {
            const fsm::Epoch opened = near(epoch, fsm::kMaxEpoch);
            version.lineage = fsm::lineage_of(opened, near(0, 4));
        }
        version.count =
            input_.ConsumeBool()
                ? base.count + input_.ConsumeIntegralInRange<std::uint64_t>(0, 3)
                : input_.ConsumeIntegralInRange<std::uint64_t>(0, fsm::kMaxVersionCount);
        return version;
    }
    std::vector<std::uint8_t> state() {
        return input_.ConsumeBytes<std::uint8_t>(
            input_.ConsumeIntegralInRange<std::size_t>(0, kMaxStateBytes));
    }

    fsm::Message typed(const fsm::NodeProtocol& at) {
        const NodeId from = any_node();
        const fsm::View& own = at.view();
        const fsm::Epoch epoch = near(at.epoch(), fsm::kMaxEpoch);
        switch (input_.ConsumeIntegralInRange<int>(0, 9)) {
            case 0: {
                fsm::Heartbeat heartbeat;
                heartbeat.from = from;
                heartbeat.epoch = epoch;
                heartbeat.incarnation = near(1, fsm::kMaxIncarnation);
                heartbeat.excluded = input_.ConsumeBool();
                heartbeat.seq =
                    near(static_cast<std::uint32_t>(cluster_.now() / period()), 0xFFFF'FFFF);
                const int acks = input_.ConsumeIntegralInRange<int>(0, cluster_.node_count());
                for (int k = 0; k < acks; ++k) {
                    heartbeat.acks.push_back(fsm::HeartbeatAck{any_node(),
                                                               near(1, fsm::kMaxIncarnation),
                                                               near(heartbeat.seq, 0xFFFF'FFFF)});
                }
                heartbeat.reply = input_.ConsumeBool();
                return heartbeat;
            }
            case 1: {
                fsm::Command command;
                command.from = from;
                command.view = view(own);
                if (input_.ConsumeBool()) command.from = command.view.master;
                const int joint = input_.ConsumeIntegralInRange<int>(0, 2);
                for (int k = 0; k < joint; ++k) {
                    command.joint.push_back(input_.ConsumeBool() ? own : view(own));
                }
                // A hand-over's receiver boot: the fuzzed nodes' (0) or any other.
                if (input_.ConsumeBool()) command.boot = input_.ConsumeIntegral<std::uint32_t>();
                return command;
            }
            case 2:
                return fsm::ActivateCommand{from, near(own.epoch, fsm::kMaxEpoch),
                                            near(own.seq, fsm::kMaxSeq)};
            case 3:
                return fsm::Ack{
                    from, near(own.epoch, fsm::kMaxEpoch), near(own.seq, fsm::kMaxSeq),
                    input_.ConsumeBool() ? fsm::AckKind::Prepared : fsm::AckKind::Activated};
            case 4:
                return fsm::ErrorNotification{from, epoch, any_node()};
            case 5: {
                const TaskId written = task();
                return fsm::CheckpointWrite{
                    from,   epoch, written, version(at, written, epoch), input_.ConsumeBool(),
                    state()};
            }
            case 6: {
                const TaskId acked = task();
                return fsm::CheckpointAck{from, epoch, acked, version(at, acked, epoch)};
            }
            case 7:
                return fsm::CheckpointRequest{from, epoch, near(own.seq, fsm::kMaxSeq), task()};
            case 8: {
                fsm::CheckpointReply reply;
                reply.from = from;
                reply.epoch = epoch;
                reply.seq = near(own.seq, fsm::kMaxSeq);
                reply.task = task();
                reply.found = input_.ConsumeBool();
                reply.version = version(at, reply.task, epoch);
                reply.state = state();
                return reply;
            }
            default:
                return fsm::PhaseRequest{
                    from, input_.ConsumeIntegralInRange<fsm::PhaseId>(
                              0, static_cast<fsm::PhaseId>(topology().phase_count()))};
        }
    }

    Cluster& cluster_;
    FuzzedDataProvider& input_;
};

}  // namespace
}  // namespace keel::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    using namespace keel::fuzz;
    // KEEL_ROOT (run-fuzz sets it) names the checkout; else the one this was built from.
    const char* root = std::getenv("KEEL_ROOT");
    const std::string folder =
        root != nullptr ? std::string(root) + "/tests/missions/images/good" : KEEL_FUZZ_IMAGES;
    for (std::size_t m = 0; m < missions.size(); ++m) missions[m] = load(folder, kMissionImages[m]);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace keel::fuzz;
    const std::span<const std::uint8_t> bytes(data, size);
    Invariants::check_decoded(bytes, keel::fsm::decode(bytes));
    if (size == 0) return 0;
    const int which = (data[0] & 1) | (((data[0] >> 2) & 1) << 1);
    const Mission& mission = *missions[static_cast<std::size_t>(which == 3 ? 2 : which)];
    const Prefixes& prefixes = mission.prefixes[(data[0] >> 1) & 1];
    FuzzedDataProvider input(data + 1, size - 1);
    const int scenario = input.ConsumeIntegralInRange<int>(0, prefixes.scenario_count() - 1);
    const int rounds = input.ConsumeIntegralInRange<int>(0, kPrefixRounds);
    Cluster cluster = prefixes.at(scenario, rounds);
    const TimeNs end = cluster.now() + kMaxRunNs;
    Run run(cluster, input);
    for (int record = 0; record < kMaxRecords && input.remaining_bytes() > 0 && cluster.now() < end;
         ++record) {
        run.record();
    }
    return 0;
}
