// Baseline numbers for docs/PERFORMANCE.md: one bottom-level build of a bumpy sphere (N x 2N quads, 4 N^2
// triangles) and 2^19 closest-hit rays, coherent (parallel, from outside) and incoherent (random directions
// from inside), on one worker thread. Not a test and not the Embree comparison (that is the bench of issue 7).
// Usage: vkas_baseline_trace [N]   (default 500: 1,000,000 triangles)
#include <vkas/vkas.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <random>
#include <cmath>
#define GET(name) auto name = (PFN_##name)vkasGetDeviceProcAddr(dev, #name)
int main(int argc, char** argv) {
  VkasDeviceCreateInfo dci{}; dci.workerThreadCount = 1; VkDevice dev; vkasCreateDevice(&dci, &dev);
  GET(vkCreateBuffer); GET(vkGetBufferMemoryRequirements); GET(vkAllocateMemory); GET(vkBindBufferMemory);
  GET(vkGetAccelerationStructureBuildSizesKHR); GET(vkCreateAccelerationStructureKHR); GET(vkBuildAccelerationStructuresKHR);
  GET(vkDestroyAccelerationStructureKHR); GET(vkDestroyBuffer); GET(vkFreeMemory);
  std::vector<VkAccelerationStructureKHR> structures; std::vector<VkBuffer> buffers; std::vector<VkDeviceMemory> memories;
  auto makeAS = [&](VkAccelerationStructureTypeKHR type, VkDeviceSize size) {
    VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO}; bci.size = size; bci.usage = VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR;
    VkBuffer buf; vkCreateBuffer(dev, &bci, nullptr, &buf);
    VkMemoryRequirements req; vkGetBufferMemoryRequirements(dev, buf, &req);
    VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO}; mai.allocationSize = req.size;
    VkDeviceMemory mem; vkAllocateMemory(dev, &mai, nullptr, &mem); vkBindBufferMemory(dev, buf, mem, 0);
    VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR}; ci.buffer = buf; ci.size = size; ci.type = type;
    VkAccelerationStructureKHR as; vkCreateAccelerationStructureKHR(dev, &ci, nullptr, &as);
    structures.push_back(as); buffers.push_back(buf); memories.push_back(mem); return as; };
  // bumpy sphere
  int N = argc>1?atoi(argv[1]):500; std::vector<float> v; std::vector<uint32_t> idx;
  std::mt19937 rng(1); std::uniform_real_distribution<float> U(0,1);
  for (int i=0;i<=N;i++) for(int j=0;j<=2*N;j++){ float th=M_PI*i/N, ph=2*M_PI*j/(2*N); float r=1+0.02f*U(rng); v.push_back(r*sinf(th)*cosf(ph)); v.push_back(r*sinf(th)*sinf(ph)); v.push_back(r*cosf(th)); }
  for (int i=0;i<N;i++) for(int j=0;j<2*N;j++){ uint32_t a=i*(2*N+1)+j; idx.insert(idx.end(),{a,a+1,a+2*N+2, a,a+2*N+2,a+2*N+1}); }
  VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR}; g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR; g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
  auto& t = g.geometry.triangles; t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR; t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT; t.vertexData.hostAddress = v.data(); t.vertexStride = 12; t.maxVertex = v.size()/3-1; t.indexType = VK_INDEX_TYPE_UINT32; t.indexData.hostAddress = idx.data();
  VkAccelerationStructureBuildGeometryInfoKHR bi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR}; bi.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR; bi.geometryCount = 1; bi.pGeometries = &g;
  uint32_t cnt = idx.size()/3; VkAccelerationStructureBuildSizesInfoKHR sz{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
  vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &bi, &cnt, &sz);
  auto blas = makeAS(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, sz.accelerationStructureSize);
  std::vector<unsigned char> scratch(sz.buildScratchSize, 0xAA);
  bi.dstAccelerationStructure = blas; bi.scratchData.hostAddress = scratch.data();
  VkAccelerationStructureBuildRangeInfoKHR r{cnt,0,0,0}; const VkAccelerationStructureBuildRangeInfoKHR* pr = &r;
  auto t0=std::chrono::steady_clock::now(); vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &bi, &pr);
  double ms = std::chrono::duration<double,std::milli>(std::chrono::steady_clock::now()-t0).count(); printf("%u tris build %.1f ms %.2f Mtris/s\n", cnt, ms, cnt/ms/1000);
  VkAccelerationStructureInstanceKHR inst{}; inst.transform.matrix[0][0]=inst.transform.matrix[1][1]=inst.transform.matrix[2][2]=1; inst.mask=0xFF; inst.accelerationStructureReference=(uint64_t)blas;
  VkAccelerationStructureGeometryKHR gi{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR}; gi.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR; gi.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR; gi.geometry.instances.data.hostAddress = &inst;
  VkAccelerationStructureBuildGeometryInfoKHR ti{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR}; ti.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR; ti.geometryCount = 1; ti.pGeometries = &gi;
  uint32_t one = 1; vkGetAccelerationStructureBuildSizesKHR(dev, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &ti, &one, &sz);
  auto tlas = makeAS(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, sz.accelerationStructureSize);
  std::vector<unsigned char> scratch2(sz.buildScratchSize, 0xAA); ti.dstAccelerationStructure = tlas; ti.scratchData.hostAddress = scratch2.data();
  VkAccelerationStructureBuildRangeInfoKHR r2{1,0,0,0}; pr = &r2; vkBuildAccelerationStructuresKHR(dev, VK_NULL_HANDLE, 1, &ti, &pr);
  int R = 1<<19; std::vector<VkasRay> rays(R); std::vector<VkasHit> hits(R);
  for (int k=0;k<2;k++) {
  for (auto& ray : rays) { if (k==0){ ray.origin[0]=-0.8f+1.6f*U(rng); ray.origin[1]=-0.8f+1.6f*U(rng); ray.origin[2]=5; ray.direction[0]=0; ray.direction[1]=0; ray.direction[2]=-1;} else { for(int c=0;c<3;c++){ray.origin[c]=0.3f*(U(rng)-0.5f); ray.direction[c]=U(rng)-0.5f;} } ray.tMin=0; ray.tMax=1e30f; }
  t0=std::chrono::steady_clock::now(); vkasTraceRays(dev, tlas, VKAS_TRACE_MODE_CLOSEST_HIT, 0, 0xFF, R, rays.data(), hits.data());
  ms = std::chrono::duration<double,std::milli>(std::chrono::steady_clock::now()-t0).count(); int h=0; for (auto& x:hits) h+= x.type!=0;
  printf("%s: %.2f Mrays/s (1 thread), hits %d/%d\n", k==0?"coherent":"incoherent", R/ms/1000, h, R);
  }
  for (auto as : structures) vkDestroyAccelerationStructureKHR(dev, as, nullptr);
  for (auto b : buffers) vkDestroyBuffer(dev, b, nullptr);
  for (auto m : memories) vkFreeMemory(dev, m, nullptr);
  vkasDestroyDevice(dev);
}
