// The glTF loader's parts (core/scene/gltf_loader.h is its interface): shared by
// gltf_file_sandbox.cpp (what tinygltf may read), gltf_images.cpp, gltf_accessors.cpp,
// gltf_materials.cpp, gltf_meshes.cpp, gltf_warnings.cpp, gltf_scene_assembly.cpp (nodes,
// cameras, lights), gltf_instancing.cpp, gltf_deformation.cpp (morph targets, skins) and
// gltf_loader.cpp (the entry points). Not for use outside core/scene/.
#pragma once

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond::gltf {

// Limits that keep hostile uploads from exhausting memory or the stack.
inline constexpr uint64_t kMaxFileBytes = uint64_t(2) << 30;  // tinygltf takes 32-bit lengths
inline constexpr int kMaxNodeDepth = 256;
inline constexpr size_t kMaxNodeVisits = size_t(1) << 20;  // bounds DAG-shaped instancing blow-ups
inline constexpr size_t kMaxSceneTriangles = size_t(1) << 25;
inline constexpr size_t kMaxSceneVertices = size_t(1) << 26;
inline constexpr uint32_t kMaxImageSide = 16384;
inline constexpr uint64_t kMaxImagePixels = uint64_t(1) << 26;
// Morph targets: the displacements decoded, and those added up while placing morphed meshes.
inline constexpr size_t kMaxMorphElements = size_t(1) << 24;
inline constexpr size_t kMaxMorphWork = size_t(1) << 28;

/// " 'name'" for a message, or nothing for an unnamed object.
inline std::string quoted(const std::string& name) { return name.empty() ? "" : " '" + name + "'"; }

inline std::string trim_trailing_whitespace(std::string text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    return text;
}

// ---------------------------------------------------------------------------------------------
// File access sandbox (gltf_file_sandbox.cpp): every path tinygltf wants to open passes through
// these callbacks.

struct FileSandbox {
    bool allow_files = false;          // false for uploads: any external uri is refused
    std::filesystem::path root;        // canonical bundle root
    std::string base_dir;              // the base directory handed to tinygltf
    std::vector<std::string> refused;  // "uri (reason)" for every refusal, in order
};

/// `dir` absolute and canonical, without a trailing separator; empty when it cannot be resolved.
std::filesystem::path canonical_directory(const std::filesystem::path& dir);
/// The file's bytes into *out, or false with the reason in *err (the path is tinygltf's to add).
bool read_whole_file(const std::filesystem::path& path, std::vector<unsigned char>* out, std::string* err);
/// tinygltf::FsCallbacks with a FileSandbox as user data.
tinygltf::FsCallbacks sandbox_callbacks(FileSandbox& sandbox);

// ---------------------------------------------------------------------------------------------
// Images (gltf_images.cpp): tinygltf hands us the encoded bytes; we keep them as-is and decode
// only the images a material actually uses, after the whole file was accepted.

struct ImageLoadContext {
    const tinygltf::Model* model = nullptr;
};

/// tinygltf's image loader: keeps the encoded bytes (user data: an ImageLoadContext).
bool keep_encoded_image(tinygltf::Image* image, const int image_index, std::string* err,
                        std::string*, int, int, const unsigned char* bytes, int size, void* user);
/// Decodes a PNG, JPEG or WebP into a texture read as sRGB colour (base colour, emission) or as data
/// (metallic-roughness, normals): 8-bit images keep their bytes (TexelEncoding), 16-bit ones
/// become float linear RGB and alpha.
Expected<Texture> decode_image(const tinygltf::Image& image, int image_index, bool srgb);

// ---------------------------------------------------------------------------------------------
// Accessors (gltf_accessors.cpp).

int component_size(int component_type);
/// The rotation of quaternion (x, y, z, w), normalized first; nullopt for a zero quaternion
/// (gltf_scene_assembly.cpp, like trs_matrix).
std::optional<Mat3> rotation_matrix(double x, double y, double z, double w);
/// Translation * Rotation * Scale, glTF's order for nodes and EXT_mesh_gpu_instancing's instances.
Mat4 trs_matrix(const Vec3& translation, const Mat3& rotation, const Vec3& scale);
int component_count(int type);
std::string type_name(int type);
std::string component_type_name(int component_type);
uint32_t read_unsigned(const uint8_t* p, int component_type);
/// glTF 2.0 section 3.11 "Animations" gives the normalized-integer to float mapping used here.
float read_float_component(const uint8_t* p, int component_type, bool normalized);

/// An accessor's elements, tightly packed, with sparse substitution applied.
struct PackedAccessor {
    std::vector<uint8_t> bytes;
    size_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
};

/// What a mesh attribute or index accessor must look like.
struct AccessorRule {
    std::vector<int> types;
    std::vector<int> float_component_types;       // accepted as they are
    std::vector<int> normalized_component_types;  // accepted only with "normalized": true
    std::vector<int> integer_component_types;     // accepted only without "normalized"
};

extern const AccessorRule kPositionRule;
extern const AccessorRule kNormalRule;
extern const AccessorRule kTexcoordRule;
extern const AccessorRule kColorRule;
extern const AccessorRule kTangentRule;
extern const AccessorRule kIndexRule;
/// Skins: JOINTS_n (joint indices), WEIGHTS_n, a skin's inverseBindMatrices.
extern const AccessorRule kJointsRule;
extern const AccessorRule kWeightsRule;
extern const AccessorRule kInverseBindMatrixRule;
/// Morph targets' displacements: POSITION, and NORMAL or TANGENT (both VEC3).
extern const AccessorRule kMorphPositionRule;
extern const AccessorRule kMorphDirectionRule;
/// EXT_mesh_gpu_instancing's instance attributes.
extern const AccessorRule kInstanceTranslationRule;
extern const AccessorRule kInstanceRotationRule;
extern const AccessorRule kInstanceScaleRule;

/// The rule an attribute follows in this file: the core rule, widened where the file declares
/// KHR_mesh_quantization.
const AccessorRule& effective_rule(const AccessorRule& rule, bool quantized);

// Converts packed float-like accessor data, refusing NaN and infinity.
template <typename VecT>
Expected<std::vector<VecT>> unpack_vectors(const PackedAccessor& packed, const std::string& what) {
    constexpr int kComponents = VecT::length();
    std::vector<VecT> out(packed.count);
    const size_t component_bytes = size_t(component_size(packed.component_type));
    const uint8_t* p = packed.bytes.data();
    for (size_t i = 0; i < packed.count; ++i) {
        for (int c = 0; c < kComponents; ++c, p += component_bytes) {
            const float v = read_float_component(p, packed.component_type, packed.normalized);
            if (!std::isfinite(v))
                return Error{what + " has a non-finite value at element " + std::to_string(i)};
            out[i][c] = v;
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Material extensions (gltf_materials.cpp).

/// A JSON number as an int: nullopt when it is not a number or lies beyond int's range.
std::optional<int> int_value(const tinygltf::Value& v);
/// A number from an extension object: the default when absent, an error when of the wrong type.
Expected<double> extension_number(const tinygltf::ExtensionMap& extensions, const char* extension,
                                  const char* key, double fallback);

// ---------------------------------------------------------------------------------------------
// The reader: one tinygltf::Model into a Scene. Its members are defined by concept in the files
// named above.

/// One primitive of a mesh as read, but its morph targets: attributes per vertex, triangles, its
/// scene material, its skin influences.
struct PrimitiveVertices {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<Vec2> uvs;
    std::vector<Vec2> uvs1;
    std::vector<Vec4> colors;
    std::vector<Vec4> tangents;
    std::vector<glm::uvec3> triangles;
    uint32_t material = 0;
    /// The slot of the normal texture whose tangents were generated here (the file gave none):
    /// a morphed copy generates its own. -1: none generated.
    int generated_tangent_slot = -1;
    /// The normals are the faces' own, made here for a primitive without NORMAL (each triangle
    /// has vertices of its own): a morphed or skinned copy makes them anew.
    bool face_normals = false;
    /// Skin influences: JOINTS_0 / WEIGHTS_0 and JOINTS_1 / WEIGHTS_1 (up to eight joints per
    /// vertex); empty when the primitive has none.
    std::array<std::vector<glm::uvec4>, 2> joints;
    std::array<std::vector<Vec4>, 2> weights;
    /// The largest joint index given a weight, and where the file gives it (for the message
    /// when a skin has fewer joints).
    uint32_t largest_joint = 0;
    std::string largest_joint_at;
};

/// A primitive as read, with its morph targets.
struct DecodedPrimitive : PrimitiveVertices {
    /// A morph target's displacements per vertex; each empty where the target has none.
    struct MorphTarget {
        std::vector<Vec3> positions;
        std::vector<Vec3> normals;
        std::vector<Vec3> tangents;
    };
    std::vector<MorphTarget> targets;
};

/// MikkTSpace-compatible tangents for `prim` from the TEXCOORD set of `slot` (gltf_meshes.cpp).
void generate_tangents(DecodedPrimitive& prim, int slot);

// Morph targets and skins (gltf_deformation.cpp): a primitive in the pose the file gives, the
// weights and joint transforms of its nodes (no animation is applied).

/// `prim` with its morph targets blended by `weights` (one per target): displacements added,
/// normals and tangents renormalized, generated tangents made anew.
DecodedPrimitive morphed(const DecodedPrimitive& prim, const std::vector<float>& weights);
/// Skins `prim` in place into world space: each vertex by the blend of its joints' matrices
/// (joint world transform times inverse bind matrix) by their weights. A vertex whose weights
/// sum to zero is placed by `unskinned` (its node's world transform). Every joint index given a
/// weight is below joint_matrices.size() (prim.largest_joint, checked by the caller).
void skin_in_place(DecodedPrimitive& prim, const std::vector<Mat4>& joint_matrices, const Mat4& unskinned);

class GltfSceneReader {
public:
    GltfSceneReader(const tinygltf::Model& model, std::string display_name)
        : model_(model), file_(std::move(display_name)), builder_(file_) {
        for (const tinygltf::Buffer& buffer : model_.buffers)
            total_buffer_bytes_ += buffer.data.size();
        const auto& used = model_.extensionsUsed;
        quantized_ = std::find(used.begin(), used.end(), "KHR_mesh_quantization") != used.end();
    }

    Expected<Scene> read();

private:
    Error fail(const std::string& message) const { return Error{file_ + ": " + message}; }

    Expected<PackedAccessor> pack_accessor(int index, const std::string& context,
                                           const std::string& role, const AccessorRule& rule);
    /// Whether an accessor's type and component type are ones `role` accepts in this file.
    Status check_accessor_rule(const tinygltf::Accessor& accessor, const std::string& what,
                               const std::string& role, const AccessorRule& core_rule) const;
    /// Sparse substitution into the packed elements.
    Status apply_sparse(const tinygltf::Accessor& accessor, const std::string& what, size_t element_size,
                        PackedAccessor& packed) const;
    Status check_view_range(int view_index, size_t byte_offset, size_t count, size_t element_size,
                            bool use_view_stride, const std::string& what, const uint8_t** data,
                            size_t* stride) const;

    Status load_mesh(int mesh_index);
    Expected<DecodedPrimitive> decode_primitive(const tinygltf::Primitive& prim, const std::string& context);
    Status read_positions(const tinygltf::Primitive& prim, const std::string& context,
                          std::vector<Vec3>& positions);
    /// An optional per-vertex attribute with the same element count as POSITION.
    template <typename VecT>
    Status read_attribute(const tinygltf::Primitive& prim, const std::string& context,
                          const std::string& name, const AccessorRule& rule, size_t vertex_count,
                          std::vector<VecT>& target);
    /// Accessor `accessor` of a per-vertex attribute (`role`: "NORMAL", "targets[1] POSITION",
    /// ...) read whole, with as many elements as POSITION.
    template <typename VecT>
    Status read_vertex_accessor(int accessor, const std::string& context, const std::string& role,
                                const AccessorRule& rule, size_t vertex_count, std::vector<VecT>& target);
    /// The same accessor packed, its element count checked; `what` names it for later messages.
    Expected<PackedAccessor> pack_vertex_accessor(int accessor, const std::string& context, const std::string& role,
                                                  const AccessorRule& rule, size_t vertex_count, std::string* what);
    /// The primitive's indices (0, 1, ... without an index accessor), each below vertex_count.
    Expected<std::vector<uint32_t>> read_indices(const tinygltf::Primitive& prim, const std::string& context,
                                                 size_t vertex_count);
    /// Triangles of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive.
    Expected<std::vector<glm::uvec3>> assemble_triangles(int mode, const std::vector<uint32_t>& indices,
                                                         const std::string& context) const;
    Expected<uint32_t> scene_material(int material_index);
    /// glTF material material_index (it exists) as a scene material, by parts: factors with the
    /// KHR_materials_* numbers, alpha mode, textures, clearcoat and volume.
    Expected<Material> read_material(int material_index);
    Status read_material_factors(const tinygltf::Material& g, const std::string& context, Material& m) const;
    Status read_alpha_mode(const tinygltf::Material& g, const std::string& context, Material& m) const;
    Status read_material_textures(const tinygltf::Material& g, int material_index, const std::string& context,
                                  Material& m);
    Status read_clearcoat_and_volume(const tinygltf::Material& g, int material_index, const std::string& context,
                                     Material& m);
    /// The textureInfo `key` of an extension's object (absent: `target` unchanged), read as sRGB
    /// colour or as data.
    Status read_extension_texture(const tinygltf::Value& extension, const char* extension_name, const char* key,
                                  int material_index, const std::string& context, TextureRef& target,
                                  bool srgb = false);
    /// The scene texture of glTF texture texture_index read as sRGB colour or as data: its index,
    /// given now; the image is decoded by decode_textures() once the whole file was accepted.
    Expected<int> scene_texture(int texture_index, const std::string& context, const std::string& role,
                                bool srgb);
    /// Decodes every texture scene_texture() handed out, in parallel (image decoding is
    /// most of the time a textured file takes to read), and adds them to the scene in the order
    /// their indices were given; the first failure in that order is the error.
    Status decode_textures();
    /// A textureInfo (index, texCoord, KHR_texture_transform) as a TextureRef; `sets` collects
    /// the material's TEXCOORD sets, whose position there is the ref's slot.
    Expected<TextureRef> texture_ref(int index, int tex_coord, const tinygltf::ExtensionMap& extensions,
                                     const std::string& context, const std::string& role, bool srgb,
                                     std::vector<int>& sets);
    Status visit_node(int node_index, const Mat4& parent, int depth);
    /// The node's mesh, every primitive, placed by `world`.
    Status add_node_mesh(const tinygltf::Node& node, int node_index, const Mat4& world);
    /// The node's EXT_mesh_gpu_instancing transforms (gltf_instancing.cpp), each applied before
    /// the node's world transform; the identity alone for a node without the extension.
    Expected<std::vector<Mat4>> instance_transforms(const tinygltf::Node& node, int node_index);
    Status add_camera(const tinygltf::Node& node, int node_index, const Mat4& world);
    void add_cameras();
    void note_dropped_primitive_features(const tinygltf::Primitive& prim);
    /// Transmissive surfaces of a mesh as solids or thin walls (Material::thin_walled): the
    /// primitives of one glTF material (`gltf_materials`, parallel to `decoded`) that together
    /// close no volume are thin walls, where the material has no KHR_materials_volume (or one of
    /// thicknessFactor 0, the specification's thin wall); closed ones stay solids, noted for
    /// add_feature_warnings where the file gives no volume.
    Status assign_thin_walls(std::vector<DecodedPrimitive>& decoded, const std::vector<int>& gltf_materials);
    /// The thin-walled copy of glTF material material_index's scene material.
    uint32_t thin_walled_material(int material_index, uint32_t solid);
    void add_feature_warnings();
    Status add_light(const tinygltf::Node& node, int node_index, const Mat4& world);
    /// A primitive's morph targets and skin influences into `out` (gltf_deformation.cpp).
    Status read_morph_targets(const tinygltf::Primitive& prim, const std::string& context, DecodedPrimitive& out);
    Status read_skin_influences(const tinygltf::Primitive& prim, const std::string& context, DecodedPrimitive& out);
    /// The node's morph weights: its own `weights`, else its mesh's, else none (all zero).
    Expected<std::vector<float>> morph_weights(const tinygltf::Node& node, int node_index) const;
    /// The node's skin as joint matrices: each joint's world transform times its inverse bind
    /// matrix (glTF 2.0 section 3.7.3); made once per skin.
    Expected<const std::vector<Mat4>*> joint_matrices(const tinygltf::Node& node, int node_index);
    /// A node's world transform through its parents (joints may lie anywhere in the hierarchy);
    /// `context` opens the message of a failure.
    Expected<Mat4> node_world(int node_index, const std::string& context);
    Expected<Mat4> local_transform(const tinygltf::Node& node, int node_index) const;



    const tinygltf::Model& model_;
    std::string file_;
    SceneBuilder builder_;
    size_t total_buffer_bytes_ = 0;
    bool quantized_ = false;  // KHR_mesh_quantization declared: integer attributes allowed
    std::vector<std::optional<std::vector<DecodedPrimitive>>> meshes_;
    std::map<int, uint32_t> materials_;  // glTF material (-1: default) -> scene material
    std::map<int, Material> material_values_;  // glTF material -> what was added as scene material
    std::map<int, uint32_t> thin_materials_;   // glTF material -> its thin-walled scene material
    /// (glTF image, sampler, sRGB) -> scene texture
    std::map<std::tuple<int, int, bool>, int> textures_;
    /// A scene texture handed out and not yet decoded: its image, sampler, curve, and the first
    /// use's context for the error message.
    struct PendingTexture {
        int image = -1;
        int sampler = -1;
        bool srgb = false;
        std::string context;
    };
    std::vector<PendingTexture> pending_textures_;  // by scene texture index
    std::map<int, std::vector<int>> texcoord_sets_;  // glTF material -> TEXCOORD sets by slot
    std::map<int, int> normal_slots_;  // glTF material with a normal texture -> its slot
    std::vector<uint8_t> on_path_;       // cycle detection during the node walk
    std::vector<int> parents_;                      // each node's parent (-1: a root)
    std::vector<std::optional<Mat4>> node_worlds_;  // node_world's results so far
    std::vector<std::optional<std::vector<Mat4>>> skin_matrices_;  // joint_matrices' by skin
    size_t morph_elements_ = 0;  // morph displacements decoded (read_morph_targets)
    size_t morph_work_ = 0;      // displacements added while placing meshes (add_node_mesh)
    std::vector<std::optional<CameraDesc>> cameras_;  // per glTF camera, from the first node
    std::vector<std::vector<int>> camera_nodes_;      // per glTF camera, the nodes placing it
    // What the walk met and drops or takes its own way, for add_feature_warnings.
    size_t skipped_point_line_primitives_ = 0;
    std::set<std::string> ignored_attributes_;      // attribute names read by nothing
    std::set<std::string> skin_warnings_;           // skins and influences not applied, as worded
    std::set<int> solid_transmission_materials_;    // on closed meshes without KHR_materials_volume
    size_t node_visits_ = 0;
    size_t triangle_count_ = 0;
    size_t vertex_count_ = 0;
};
}  // namespace photond::gltf
