#error "a consumer of vcar::vcar alone reached nlohmann/json_fwd.hpp: <vcar/vcar.hpp> must not need it"
