#error "a consumer of vcar::vcar alone reached stb/stb_image_write.h: <vcar/vcar.hpp> must not need it"
