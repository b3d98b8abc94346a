#include "core/net/dds/sampled.hpp"

#include <dds/dds.h>

#include <algorithm>
#include <array>

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
        participant = check(dds_create_participant(config.domain_id, nullptr, nullptr),
                            "dds_create_participant");
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

// The QoS both sides use; the writer adds its strength.
dds_qos_t* sampled_qos(const SampledConfig& config) {
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
    dds_qset_ownership(qos, DDS_OWNERSHIP_EXCLUSIVE);
    dds_qset_liveliness(qos, DDS_LIVELINESS_MANUAL_BY_TOPIC,
                        std::chrono::duration_cast<std::chrono::nanoseconds>(config.lease).count());
    return qos;
}

}  // namespace

struct SampledPublisher::Impl {
    Base base;
    dds_entity_t writer = 0;
    keel_sampled_Sample sample{};

    Impl(const SampledConfig& config, std::uint16_t stream, std::int32_t strength) : base(config) {
        dds_qos_t* qos = sampled_qos(config);
        dds_qset_ownership_strength(qos, strength);
        writer = dds_create_writer(base.participant, base.topic, qos, nullptr);
        dds_delete_qos(qos);
        check(writer, "dds_create_writer(KeelSampled)");
        sample.stream = stream;
        sample.writer = config.address;
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
    Base base;
    dds_entity_t reader = 0;
    dds_entity_t waitset = 0;

    explicit Impl(const SampledConfig& config) : base(config) {
        dds_qos_t* qos = sampled_qos(config);
        reader = dds_create_reader(base.participant, base.topic, qos, nullptr);
        dds_delete_qos(qos);
        check(reader, "dds_create_reader(KeelSampled)");
        waitset = check(dds_create_waitset(base.participant), "dds_create_waitset");
        const dds_entity_t condition = check(
            dds_create_readcondition(reader, DDS_ANY_STATE), "dds_create_readcondition");
        check(dds_waitset_attach(waitset, condition, reader), "dds_waitset_attach");
    }
};

SampledSubscriber::SampledSubscriber(const SampledConfig& config)
    : impl_(std::make_unique<Impl>(config)) {}
SampledSubscriber::~SampledSubscriber() = default;

bool SampledSubscriber::wait(std::chrono::nanoseconds timeout) {
    return dds_waitset_wait(impl_->waitset, nullptr, 0, timeout.count()) > 0;
}

std::size_t SampledSubscriber::take(std::vector<SampledSample>& out, std::size_t max_items) {
    constexpr std::size_t batch = 16;
    std::size_t taken = 0;
    while (taken < max_items) {
        std::array<void*, batch> samples{};
        std::array<dds_sample_info_t, batch> infos{};
        const std::size_t want = std::min(batch, max_items - taken);
        const dds_return_t count = dds_take(impl_->reader, samples.data(), infos.data(), want,
                                            static_cast<std::uint32_t>(want));
        if (count <= 0) break;
        for (dds_return_t i = 0; i < count; ++i) {
            const auto index = static_cast<std::size_t>(i);
            if (!infos[index].valid_data) continue;
            const auto* sample = static_cast<const keel_sampled_Sample*>(samples[index]);
            SampledSample item;
            item.stream = sample->stream;
            item.writer = sample->writer;
            item.sequence = sample->sequence_number;
            item.timestamp_ns = sample->timestamp_ns;
            item.payload.assign(sample->payload._buffer, sample->payload._buffer + sample->payload._length);
            out.push_back(std::move(item));
            ++taken;
        }
        dds_return_loan(impl_->reader, samples.data(), count);
    }
    return taken;
}

std::size_t SampledSubscriber::matched_writers() const {
    dds_subscription_matched_status_t status{};
    if (dds_get_subscription_matched_status(impl_->reader, &status) < 0) return 0;
    return status.current_count;
}

}  // namespace keel::net::dds
