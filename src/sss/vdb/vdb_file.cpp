// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file vdb_file.cpp
/// OpenVDB files: a brick map's grids written (brickmake out.vdb), .vdb files
/// read and described (brickinfo). The layout of the grids is in vdb.h and
/// docs/brickmake.md ("OpenVDB output").

#include "sss/vdb/vdb.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "sss/brick/brickmap_tools.h"
#include "sss/brick/brickmap_voxels.h"
#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"
#include "sss/util/version.h"

namespace sss {

namespace {

void initialize_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

/// io::File writes through a stream whose failures it does not check (a full
/// disk would leave a short file); this writes the same archive (seekable,
/// as io::File does) into a stream that throws on any failure.
class CheckedArchive : public openvdb::io::Archive {
public:
    void write_checked(const std::string& path, const openvdb::GridCPtrVec& grids,
                       const openvdb::MetaMap& meta) const {
        std::ofstream os;
        os.exceptions(std::ios::failbit | std::ios::badbit);
        try {
            os.open(path, std::ios::out | std::ios::binary | std::ios::trunc);
            Archive::write(os, grids, /*seekable=*/true, meta);
            os.close();
        } catch (const std::ios_base::failure&) {
            throw IoError(path,
                          "cannot write the OpenVDB file (disk full or not writable)");
        }
    }
};

std::string class_name(openvdb::GridClass c) {
    switch (c) {
    case openvdb::GRID_LEVEL_SET:
        return "level set";
    case openvdb::GRID_FOG_VOLUME:
        return "fog volume";
    case openvdb::GRID_STAGGERED:
        return "staggered";
    default:
        return "unknown";
    }
}

/// A grid's description; the voxel count and box from its tree when it has
/// one, else from the file's statistics metadata (file_voxel_count, ...).
VdbGridInfo grid_info(const openvdb::GridBase& grid, bool has_tree) {
    VdbGridInfo info;
    info.name = grid.getName();
    info.value_type = grid.valueType();
    info.grid_class = class_name(grid.getGridClass());
    const openvdb::math::Transform& xf = grid.transform();
    info.linear = xf.isLinear();
    const openvdb::Vec3d size = xf.voxelSize();
    const openvdb::Vec3d origin = xf.indexToWorld(openvdb::Vec3d(0.0));
    for (int a = 0; a < 3; ++a) {
        info.voxel_size[a] = size[a];
        info.origin[a] = origin[a];
    }
    openvdb::CoordBBox box;
    if (has_tree) {
        info.voxels = static_cast<std::size_t>(grid.activeVoxelCount());
        box = grid.evalActiveVoxelBoundingBox();
    } else {
        if (auto n = grid.getMetadata<openvdb::Int64Metadata>("file_voxel_count"))
            info.voxels = static_cast<std::size_t>(n->value());
        auto lo = grid.getMetadata<openvdb::Vec3IMetadata>("file_bbox_min");
        auto hi = grid.getMetadata<openvdb::Vec3IMetadata>("file_bbox_max");
        if (lo && hi)
            box = openvdb::CoordBBox(openvdb::Coord(lo->value()),
                                     openvdb::Coord(hi->value()));
    }
    if (info.voxels > 0 && !box.empty()) {
        for (int a = 0; a < 3; ++a) {
            info.index_min[a] = box.min()[a];
            info.index_max[a] = box.max()[a];
        }
    }
    for (auto it = grid.beginMeta(); it != grid.endMeta(); ++it) {
        const std::string& key = it->first;
        if (key.rfind("file_", 0) == 0 || key == "name" || key == "class") continue;
        info.metadata.emplace_back(key, it->second->str());
    }
    return info;
}

/// A grid of one channel: float grids for float channels, vec3s for colors.
openvdb::GridBase::Ptr channel_grid(const BrickMapVoxels& v, int data_size, int offset,
                                    ChannelType type) {
    openvdb::GridBase::Ptr base;
    if (type == ChannelType::Color) {
        auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        auto acc = grid->getAccessor();
        for (std::size_t i = 0; i < v.coords.size(); ++i) {
            const float* x = v.values.data() + i * data_size + offset;
            const auto& c = v.coords[i];
            acc.setValue(openvdb::Coord(c[0], c[1], c[2]),
                         openvdb::Vec3s(x[0], x[1], x[2]));
        }
        // Colours do not turn with the grid: an invariant vector.
        grid->setVectorType(openvdb::VEC_INVARIANT);
        base = grid;
    } else {
        auto grid = openvdb::FloatGrid::create(0.0f);
        auto acc = grid->getAccessor();
        for (std::size_t i = 0; i < v.coords.size(); ++i) {
            const auto& c = v.coords[i];
            acc.setValue(openvdb::Coord(c[0], c[1], c[2]),
                         v.values[i * data_size + offset]);
        }
        base = grid;
    }
    // Voxel (i, j, k) is the lattice point origin + spacing * (i, j, k).
    auto xf = openvdb::math::Transform::createLinearTransform(v.spacing);
    xf->postTranslate(openvdb::Vec3d(v.origin.x, v.origin.y, v.origin.z));
    base->setTransform(xf);
    base->setSaveFloatAsHalf(false);
    return base;
}

/// The grids of every channel for one depth's voxels.
void add_grids(const BrickMap& map, const BrickMapVoxels& v, int level,
               openvdb::GridPtrVec& grids) {
    const BrickMapInfo& info = map.info();
    int offset = 0;
    for (const auto& [name, type] : info.channels) {
        openvdb::GridBase::Ptr grid = channel_grid(v, info.data_size, offset, type);
        offset += channel_type_size(type);
        grid->setName(level == 0 ? name : name + "_level" + std::to_string(level));
        grid->insertMeta("sss_channel", openvdb::StringMetadata(name));
        grid->insertMeta("sss_channel_type",
                         openvdb::StringMetadata(channel_type_name(type)));
        grid->insertMeta("sss_level", openvdb::Int32Metadata(level));
        grid->insertMeta("sss_brick_depth", openvdb::Int32Metadata(v.depth));
        grids.push_back(grid);
    }
}

/// Opens a .vdb file for reading; FormatError when OpenVDB cannot read it.
void open_vdb(openvdb::io::File& file, const std::string& path) {
    detail::require_regular_file(path);
    try {
        file.open(/*delayLoad=*/false);
    } catch (const openvdb::Exception& e) {
        throw FormatError(path,
                          std::string("not a readable OpenVDB file (") + e.what() + ")");
    }
}

std::string vec_text(const glm::dvec3& v) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%g %g %g", v.x, v.y, v.z);
    return buf;
}

} // namespace

bool is_vdb_path(const std::string& path) {
    if (path.size() < 4) return false;
    std::string ext = path.substr(path.size() - 4);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext == ".vdb";
}

VdbWriteReport write_brick_map_vdb(const BrickMap& map, const std::string& path) {
    initialize_openvdb();
    VdbWriteReport report;
    report.surface_depth = brick_map_surface_depth(map);
    openvdb::GridPtrVec grids;
    for (int level = 0; level <= report.surface_depth; ++level)
        add_grids(map, brick_map_voxels(map, report.surface_depth - level), level, grids);
    openvdb::MetaMap meta;
    meta.insertMeta("creator",
                    openvdb::StringMetadata(std::string("sss ") + version_string()));
    meta.insertMeta("sss_provenance", openvdb::StringMetadata(map.info().provenance));

    AtomicOutput out(path);
    openvdb::GridCPtrVec written(grids.begin(), grids.end());
    CheckedArchive().write_checked(out.temp_path(), written, meta);
    out.commit();
    for (const openvdb::GridBase::Ptr& g : grids)
        report.grids.push_back(grid_info(*g, true));
    std::error_code ec;
    const auto size = std::filesystem::file_size(out.destination(), ec);
    report.file_size = ec ? 0 : static_cast<uint64_t>(size);
    return report;
}

VdbMakeReport make_vdb_from_files(const std::vector<std::string>& inputs,
                                  const BrickMapBuildOptions& options,
                                  const std::string& output) {
    // The brick map is scratch data: a temporary beside the output (or in
    // $TMPDIR for a device or FIFO output), never committed, so removed.
    std::string scratch_name = output + ".bkm";
    if (writes_into_existing(output)) {
        const char* tmp = std::getenv("TMPDIR");
        scratch_name = std::string(tmp && *tmp ? tmp : "/tmp") + "/brickmake.bkm";
    }
    AtomicOutput scratch(scratch_name);
    VdbMakeReport report;
    report.build = make_brick_map_from_files(inputs, options, scratch.temp_path());
    const BrickMap map(scratch.temp_path());
    report.vdb = write_brick_map_vdb(map, output);
    return report;
}

std::vector<VdbGrid> read_vdb_grids(const std::string& path) {
    initialize_openvdb();
    openvdb::io::File file(path);
    open_vdb(file, path);
    openvdb::GridPtrVecPtr grids;
    try {
        grids = file.getGrids();
    } catch (const openvdb::Exception& e) {
        throw FormatError(path, std::string("cannot read its grids (") + e.what() + ")");
    }
    std::vector<VdbGrid> out;
    for (const openvdb::GridBase::Ptr& base : *grids) {
        VdbGrid g;
        if (auto fg = openvdb::gridPtrCast<openvdb::FloatGrid>(base)) {
            fg->tree().voxelizeActiveTiles();
            for (auto it = fg->cbeginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                g.coords.push_back({c.x(), c.y(), c.z()});
                g.values.push_back(*it);
            }
        } else if (auto vg = openvdb::gridPtrCast<openvdb::Vec3SGrid>(base)) {
            g.components = 3;
            vg->tree().voxelizeActiveTiles();
            for (auto it = vg->cbeginValueOn(); it; ++it) {
                const openvdb::Coord c = it.getCoord();
                g.coords.push_back({c.x(), c.y(), c.z()});
                for (int k = 0; k < 3; ++k) g.values.push_back((*it)[k]);
            }
        } else {
            continue;
        }
        g.info = grid_info(*base, true);
        // Index order, whatever order the tree's iterator took.
        std::vector<std::size_t> order(g.coords.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return g.coords[a] < g.coords[b];
        });
        VdbGrid sorted;
        sorted.info = g.info;
        sorted.components = g.components;
        for (std::size_t i : order) {
            sorted.coords.push_back(g.coords[i]);
            for (int k = 0; k < g.components; ++k)
                sorted.values.push_back(g.values[i * g.components + k]);
        }
        out.push_back(std::move(sorted));
    }
    file.close();
    return out;
}

std::string describe_vdb_file(const std::string& path) {
    initialize_openvdb();
    openvdb::io::File file(path);
    open_vdb(file, path);
    std::ostringstream out;
    out << "file: " << path << "\n";
    out << "format: OpenVDB " << file.version() << "\n";
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec) out << "file size: " << size << " bytes\n";
    openvdb::GridPtrVecPtr grids;
    try {
        if (openvdb::MetaMap::Ptr meta = file.getMetadata()) {
            for (auto it = meta->beginMeta(); it != meta->endMeta(); ++it)
                out << it->first << ": " << it->second->str() << "\n";
        }
        grids = file.readAllGridMetadata();
    } catch (const openvdb::Exception& e) {
        throw FormatError(path, std::string("cannot read its grids (") + e.what() + ")");
    }
    out << "grids: " << grids->size() << "\n";
    for (const openvdb::GridBase::Ptr& g : *grids) {
        const VdbGridInfo info = grid_info(*g, false);
        out << "  " << info.name << ": " << info.value_type << ", " << info.voxels
            << " active voxels, voxel size " << vec_text(info.voxel_size) << ", class "
            << info.grid_class << (info.linear ? "" : ", non-linear transform") << "\n";
        if (info.voxels > 0) {
            glm::dvec3 lo, hi;
            const openvdb::Vec3d a = g->transform().indexToWorld(
                openvdb::Vec3d(info.index_min[0], info.index_min[1], info.index_min[2]));
            const openvdb::Vec3d b = g->transform().indexToWorld(
                openvdb::Vec3d(info.index_max[0], info.index_max[1], info.index_max[2]));
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(a[k], b[k]);
                hi[k] = std::max(a[k], b[k]);
            }
            out << "    voxel centres: index [" << info.index_min[0] << " "
                << info.index_min[1] << " " << info.index_min[2] << "] .. ["
                << info.index_max[0] << " " << info.index_max[1] << " "
                << info.index_max[2] << "], world min " << vec_text(lo) << " max "
                << vec_text(hi) << "\n";
        }
        for (const auto& [key, value] : info.metadata)
            out << "    " << key << ": " << value << "\n";
    }
    file.close();
    return out.str();
}

std::string vdb_file_problem(const std::string& path) {
    try {
        initialize_openvdb();
        openvdb::io::File file(path);
        open_vdb(file, path);
        file.close();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

} // namespace sss
