#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>
#include "engine_test_util.h"
using namespace sss; using namespace sss::test;
TEST(Scratch, A) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.world_to_camera = glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 5));
    cam.perspective = true; cam.fov = 90; cam.xres = 200; cam.yres = 100;
    Primitive prim;
    prim.object_to_world = glm::scale(glm::translate(Matrix4(1.0), glm::dvec3(0, 3, 0)), glm::dvec3(2, 1, 1));
    ShadingBatch b = plane_grid(1, 1);
    b.primitive = &prim;
    ShaderInstance inst = e.instance(R"(
surface t() {
    point w = transform("object", "world", P);
    printf("P %p w %p\n", P, w);
    printf("a %p b %p\n", transform("world", "object", w), transform("object", P));
    printf("c %p\n", transform("world", "current", transform("world", P)));
    printf("d %p %p\n", transform("NDC", P), transform("NDC", "current", transform("NDC", P)));
    printf("e %p %p\n", transform("raster", "screen", transform("raster", P)), transform("screen", P));
}
)");
    e.context.execute(inst, b);
    for (auto& m : e.services.messages) printf("%s", m.c_str());
}
