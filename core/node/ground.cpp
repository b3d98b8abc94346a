#include "core/node/ground.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <sstream>
#include <variant>

#include "core/fsm/json.hpp"

namespace keel::node {

namespace {

std::optional<std::string> from_hex(std::string_view hex) {
    if (hex.empty() || hex.size() % 2 != 0 || hex.size() > 512) return std::nullopt;
    std::string out;
    out.reserve(hex.size() / 2);
    for (std::size_t i = 0; i < hex.size(); i += 2) {
        unsigned value = 0;
        const auto [end, error] = std::from_chars(hex.data() + i, hex.data() + i + 2, value, 16);
        if (error != std::errc{} || end != hex.data() + i + 2) return std::nullopt;
        out += static_cast<char>(value);
    }
    return out;
}

std::vector<std::string> words_of(std::string_view text) {
    std::vector<std::string> words;
    std::istringstream in{std::string(text)};
    for (std::string word; in >> word;) words.push_back(word);
    return words;
}

const GroundVerb* find_verb(std::string_view name) {
    const auto found = std::find_if(kGroundVerbs.begin(), kGroundVerbs.end(),
                                    [&](const GroundVerb& verb) { return verb.name == name; });
    return found == kGroundVerbs.end() ? nullptr : &*found;
}

}  // namespace

GroundGate::GroundGate(bool secured, std::optional<net::dds::OperatorIdentity> operator_identity,
                       std::string operator_problem, std::string image_prefix, std::uint64_t last_seq)
    : secured_(secured),
      identity_(std::move(operator_identity)),
      operator_problem_(std::move(operator_problem)),
      image_prefix_(std::move(image_prefix)),
      last_seq_(last_seq) {}

GroundRefusal GroundGate::refuse(std::string kind, std::string why) {
    ++refused_[kind];
    return GroundRefusal{std::move(kind), std::move(why)};
}

std::variant<GroundCommand, GroundRefusal> GroundGate::admit(std::string_view signed_line,
                                                             std::time_t now, bool durable) {
    while (!signed_line.empty() && signed_line.front() == ' ') signed_line.remove_prefix(1);
    const std::size_t space = signed_line.find(' ');
    if (space == std::string_view::npos) {
        return refuse("malformed", "expected `ground SIGNATURE COMMAND`");
    }
    const auto signature = from_hex(signed_line.substr(0, space));
    std::string_view text = signed_line.substr(space + 1);
    while (!text.empty() && (text.back() == '\r' || text.back() == '\n')) text.remove_suffix(1);
    if (!signature) return refuse("malformed", "the signature is not hex (DER ECDSA, at most 256 bytes)");
    if (!identity_) {
        return refuse("signature", secured_ ? "this node has no valid operator identity to check a signature "
                                              "with (" + operator_problem_ + ")"
                                            : "this node has no operator identity to check a signature with "
                                              "(it runs without security)");
    }
    if (!identity_->verifies(text, *signature)) {
        return refuse("signature", "the signature is not the operator's (" + identity_->subject() +
                                       ") for this command");
    }
    if (auto why = identity_->expiry_problem(now)) return refuse("expired", *why);
    const std::vector<std::string> words = words_of(text);
    if (words.size() < 4 || words[0] != "keel-ground/1" || words[1].rfind("image=", 0) != 0 ||
        words[2].rfind("seq=", 0) != 0) {
        return refuse("malformed", "expected `keel-ground/1 image=IMAGE seq=SEQ VERB ARG...`");
    }
    GroundCommand command;
    command.text = std::string(text);
    const std::string image = words[1].substr(6);
    if (!image_prefix_.empty() && image != image_prefix_) {
        return refuse("image", "the command is for image " + image + ", this node flies " + image_prefix_);
    }
    const std::string seq_text = words[2].substr(4);
    const auto [end, error] =
        std::from_chars(seq_text.data(), seq_text.data() + seq_text.size(), command.seq);
    if (error != std::errc{} || end != seq_text.data() + seq_text.size() || command.seq == 0 ||
        command.seq > static_cast<std::uint64_t>(INT64_MAX)) {
        return refuse("malformed", "seq=" + seq_text + " is not a number in 1..2^63-1");
    }
    command.verb = words[3];
    command.arguments.assign(words.begin() + 4, words.end());
    const GroundVerb* verb = find_verb(command.verb);
    if (verb == nullptr) return refuse("malformed", "unknown verb '" + command.verb + "'");
    if (command.arguments.size() != verb->arguments) {
        return refuse("malformed", "'" + command.verb + "' takes " + std::to_string(verb->arguments) +
                                       " argument(s), got " + std::to_string(command.arguments.size()));
    }
    if (!identity_->permits(command.verb)) {
        return refuse("verb", "the operator's permissions do not grant '" + command.verb + "'");
    }
    if (command.seq <= last_seq_) {
        return refuse("replay", "seq " + std::to_string(command.seq) + " is not above " +
                                    std::to_string(last_seq_) + ", the last this node admitted");
    }
    if (!durable) {
        return refuse("unsaved", "this node cannot save seq " + std::to_string(command.seq) +
                                     " before it acts (no --storage-db, or its disk failed): a replay "
                                     "after a restart could not be refused");
    }
    last_seq_ = command.seq;
    ++accepted_;
    return command;
}

std::optional<GroundRefusal> GroundGate::admit_unsigned(std::string_view verb) {
    if (!secured_) {
        ++accepted_;
        return std::nullopt;
    }
    return refuse("unsigned", "'" + std::string(verb) +
                                  "' is a ground command: this node takes it only signed by the "
                                  "operator (`ground SIGNATURE COMMAND`)");
}

std::string GroundGate::json() const {
    fsm::JsonObject refused;
    for (const auto& [kind, count] : refused_) refused.field(kind, count);
    return fsm::JsonObject()
        .field("accepted", accepted_)
        .field("last_seq", last_seq_)
        .raw("refused", refused.str())
        .str();
}

}  // namespace keel::node
