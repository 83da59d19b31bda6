#pragma once
// Internal to the completion module: the stage-3 network of a CompletionModel, and plane proxies
// as its input. Shared by ParametricCompleter and the hidden-extent head.
#include <paco/completion/network.h>
#include <paco/encoding/completion_model_impl.h>
#include <paco/encoding/plane_proxy_encoder.h>

namespace paco::detail {

/// Builds (once per model) the stage-3 network from the model file and loads its weights.
/// Call with impl.mutex held.
CompletionDecoder decoderOf(CompletionModel::Impl& impl);

/// One batch (B = 1) of the decoder's input from stage 2's plain proxies.
PlaneProxyOutput decoderInputOf(const PlaneProxies& proxies);

}  // namespace paco::detail
