#include "core/net/dds/sampled.hpp"

#include <dds/dds.h>

#include <algorithm>
#include <array>
#include <map>
#include <optional>

#include "core/net/dds/security_qos.hpp"
#include "sampled.h"

namespace keel::net::dds {

namespace {

dds_entity_t check(dds_entity_t result, const char* what) {
    if (result < 0) throw DdsError(std::string(what) + ": " + dds_strretcode(-result));
    return result;
}

DdsConfig transport_config(const SampledConfig& config) {
    DdsConfig dds;
    dds.address = config.address;
    dds.domain_id = config.domain_id;
    dds.network_interface = config.network_interface;
    dds.peers = config.peers;
    return dds;
}

// The participant, the domain (when this object created it) and the topic.
struct Base {
    dds_entity_t domain = 0;
    dds_entity_t participant = 0;
    dds_entity_t topic = 0;

    explicit Base(const SampledConfig& config) {
        const std::string xml = domain_config_xml(transport_config(config));
        const dds_entity_t created = dds_create_domain(config.domain_id, xml.c_str());
        // Another object of this process may have created the domain already: reuse it.
        if (created >= 0) domain = created;
        else if (created != DDS_RETCODE_PRECONDITION_NOT_MET) check(created, "dds_create_domain");
        dds_qos_t* participant_qos =
            config.security.enabled() ? new_security_qos(config.security) : nullptr;
        participant = dds_create_participant(config.domain_id, participant_qos, nullptr);
        if (participant_qos != nullptr) dds_delete_qos(participant_qos);
        check(participant, "dds_create_participant");
        topic = check(dds_create_topic(participant, &keel_sampled_Sample_desc, sampled_topic_name,
                                       nullptr, nullptr),
                      "dds_create_topic(KeelSampled)");
    }
    ~Base() {
        if (participant > 0) dds_delete(participant);
        if (domain > 0) dds_delete(domain);
    }
    Base(const Base&) = delete;
    Base& operator=(const Base&) = delete;
};

// A publisher or subscriber in one partition: a publisher of node N speaks in keel.from.N
// (the sender partition its permissions grant), a subscriber reads every sender's.
dds_entity_t in_partition(dds_entity_t participant, bool publisher, const std::string& name) {
    dds_qos_t* qos = dds_create_qos();
    const char* names[] = {name.c_str()};
    dds_qset_partition(qos, 1, names);
    const dds_entity_t entity = publisher ? dds_create_publisher(participant, qos, nullptr)
                                          : dds_create_subscriber(participant, qos, nullptr);
    dds_delete_qos(qos);
    return check(entity, publisher ? "dds_create_publisher" : "dds_create_subscriber");
}

// The QoS both sides use.
dds_qos_t* sampled_qos(const SampledConfig& config) {
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_liveliness(qos, DDS_LIVELINESS_MANUAL_BY_TOPIC,
                        std::chrono::duration_cast<std::chrono::nanoseconds>(config.lease).count());
    return qos;
}

SampledSample from_wire(const keel_sampled_Sample& sample) {
    SampledSample item;
    item.stream = sample.stream;
    item.writer = sample.writer;
    item.strength = sample.strength;
    item.sequence = sample.sequence_number;
    item.timestamp_ns = sample.timestamp_ns;
    item.payload.assign(sample.payload._buffer, sample.payload._buffer + sample.payload._length);
    return item;
}

}  // namespace

struct SampledPublisher::Impl {
    Base base;
    dds_entity_t writer = 0;
    keel_sampled_Sample sample{};

    Impl(const SampledConfig& config, std::uint16_t stream, std::int32_t strength) : base(config) {
        dds_qos_t* qos = sampled_qos(config);
        writer = dds_create_writer(in_partition(base.participant, true, sender_partition(config.address)),
                                   base.topic, qos, nullptr);
        dds_delete_qos(qos);
        check(writer, "dds_create_writer(KeelSampled)");
        sample.stream = stream;
        sample.writer = config.address;
        sample.strength = strength;
    }
};

SampledPublisher::SampledPublisher(const SampledConfig& config, std::uint16_t stream,
                                   std::int32_t strength)
    : impl_(std::make_unique<Impl>(config, stream, strength)) {}
SampledPublisher::~SampledPublisher() = default;

bool SampledPublisher::write(std::uint64_t sequence, std::int64_t timestamp_ns,
                             std::span<const std::uint8_t> payload) {
    keel_sampled_Sample& sample = impl_->sample;
    sample.sequence_number = sequence;
    sample.timestamp_ns = timestamp_ns;
    sample.payload._buffer = const_cast<std::uint8_t*>(payload.data());
    sample.payload._length = static_cast<std::uint32_t>(payload.size());
    sample.payload._maximum = static_cast<std::uint32_t>(payload.size());
    sample.payload._release = false;
    const dds_return_t rc = dds_write(impl_->writer, &sample);
    sample.payload._buffer = nullptr;
    return rc == DDS_RETCODE_OK;
}

std::size_t SampledPublisher::matched_readers() const {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(impl_->writer, &status) < 0) return 0;
    return status.current_count;
}

struct SampledSubscriber::Impl {
    struct Publisher {
        bool alive = false;
        std::int32_t strength = 0;
        std::optional<SampledSample> latest;  // not yet delivered when `fresh`
        bool fresh = false;
    };

    Base base;
    dds_entity_t reader = 0;
    dds_entity_t waitset = 0;
    std::map<NodeAddress, Publisher> publishers;
    int following = -1;
    std::uint64_t switches = 0;

    explicit Impl(const SampledConfig& config) : base(config) {
        dds_qos_t* qos = sampled_qos(config);
        reader = dds_create_reader(in_partition(base.participant, false, "keel.from.*"), base.topic,
                                   qos, nullptr);
        dds_delete_qos(qos);
        check(reader, "dds_create_reader(KeelSampled)");
        waitset = check(dds_create_waitset(base.participant), "dds_create_waitset");
        const dds_entity_t condition = check(
            dds_create_readcondition(reader, DDS_ANY_STATE), "dds_create_readcondition");
        check(dds_waitset_attach(waitset, condition, reader), "dds_waitset_attach");
    }

    // The strongest live publisher (ties: the lower address), or -1.
    int strongest() const {
        int best = -1;
        std::int32_t best_strength = 0;
        for (const auto& [address, publisher] : publishers) {
            if (!publisher.alive) continue;
            if (best < 0 || publisher.strength > best_strength) {
                best = address;
                best_strength = publisher.strength;
            }
        }
        return best;
    }
};

SampledSubscriber::SampledSubscriber(const SampledConfig& config)
    : impl_(std::make_unique<Impl>(config)) {}
SampledSubscriber::~SampledSubscriber() = default;

bool SampledSubscriber::wait(std::chrono::nanoseconds timeout) {
    return dds_waitset_wait(impl_->waitset, nullptr, 0, timeout.count()) > 0;
}

std::size_t SampledSubscriber::take(std::vector<SampledSample>& out) {
    Impl& impl = *impl_;
    constexpr std::size_t batch = 16;
    for (;;) {
        std::array<void*, batch> samples{};
        std::array<dds_sample_info_t, batch> infos{};
        const dds_return_t count =
            dds_take(impl.reader, samples.data(), infos.data(), batch, static_cast<std::uint32_t>(batch));
        if (count <= 0) break;
        for (dds_return_t i = 0; i < count; ++i) {
            const auto index = static_cast<std::size_t>(i);
            const auto* sample = static_cast<const keel_sampled_Sample*>(samples[index]);
            // Key fields are valid in every sample, data or instance-state change.
            Impl::Publisher& publisher = impl.publishers[sample->writer];
            if (infos[index].valid_data) {
                publisher.alive = true;
                publisher.strength = sample->strength;
                publisher.latest = from_wire(*sample);
                publisher.fresh = true;
            } else if (infos[index].instance_state != DDS_ALIVE_INSTANCE_STATE) {
                publisher.alive = false;  // lease expired or writer gone
            }
        }
        dds_return_loan(impl.reader, samples.data(), count);
        if (static_cast<std::size_t>(count) < batch) break;
    }
    const int strongest = impl.strongest();
    const bool switched = strongest != impl.following && impl.following >= 0 && strongest >= 0;
    if (strongest != impl.following) {
        if (switched) ++impl.switches;
        impl.following = strongest;
    }
    if (strongest < 0) return 0;
    Impl::Publisher& followed = impl.publishers[static_cast<NodeAddress>(strongest)];
    // On a switch the new publisher's latest sample is delivered even if it arrived while
    // another publisher was followed: it is at most one period old.
    if (!followed.latest || (!followed.fresh && !switched)) return 0;
    SampledSample item = *followed.latest;
    item.switched = switched;
    followed.fresh = false;
    for (auto& [address, publisher] : impl.publishers) publisher.fresh = false;
    out.push_back(std::move(item));
    return 1;
}

std::size_t SampledSubscriber::matched_writers() const {
    dds_subscription_matched_status_t status{};
    if (dds_get_subscription_matched_status(impl_->reader, &status) < 0) return 0;
    return status.current_count;
}

int SampledSubscriber::following() const { return impl_->following; }
std::uint64_t SampledSubscriber::switches() const { return impl_->switches; }

}  // namespace keel::net::dds
