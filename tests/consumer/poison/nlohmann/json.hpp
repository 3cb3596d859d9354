#error "a consumer of vcar::vcar alone reached nlohmann/json.hpp: <vcar/vcar.hpp> must not need it"
