#error "a consumer of vcar::vcar alone reached stb_image.h: <vcar/vcar.hpp> must not need it"
