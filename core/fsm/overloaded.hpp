// Overloaded: one visitor from several lambdas, for std::visit over the protocol's variants
// (messages, actions) wherever they are taken apart.
#pragma once

namespace keel::fsm {

template <class... F>
struct Overloaded : F... {
    using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace keel::fsm
