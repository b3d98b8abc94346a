#include "core/fsm/actions.hpp"

namespace keel::fsm {

void Outbox::send(NodeId to, Message message) { actions_.push_back(act::Send{to, std::move(message)}); }

void Outbox::push(Action action) { actions_.push_back(std::move(action)); }

}  // namespace keel::fsm
