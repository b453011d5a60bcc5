// GLSL programs built from the shaders embedded at build time, with `#include "common/x.glsl"`
// resolved from the same set. Compile errors name the file and line they come from.
#pragma once

#include "renderer/gpu/gl_objects.hpp"

#include <glm/glm.hpp>

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace bounce::gpu {

struct ProgramSource {
    std::string vertex;    // path relative to shaders/, e.g. "passes/gbuffer.vert"
    std::string fragment;  // may be empty for depth-only programs
    std::vector<std::string> defines;  // "NAME" or "NAME VALUE"
    std::string geometry;  // optional
    std::string compute;   // a compute program: set this alone (vertex and fragment empty)

    static ProgramSource compute_shader(std::string path, std::vector<std::string> defines = {}) {
        return {"", "", std::move(defines), "", std::move(path)};
    }

    std::string key() const;
};

// A GLSL source with its includes expanded, and the file name behind each `#line` source number.
struct ExpandedSource {
    std::string text;
    std::vector<std::string> files;
};

// Every GLSL file under shaders/, by its path there (defined in the source cmake/EmbedShaders.cmake
// generates).
const std::map<std::string, std::string_view>& embedded_shader_files();

// Expands `path` from the embedded files (each include once). Throws Error naming the missing file
// and who included it.
ExpandedSource expand_shader_source(const std::string& path, const std::vector<std::string>& defines);

// Rewrites a driver's info log so "0:12(3)" and "0(12)" name the file: "common/brdf.glsl:12(3)".
std::string annotate_info_log(const std::string& log, const std::vector<std::string>& files);

class ShaderProgram {
public:
    // Throws Error with the annotated compile or link log.
    explicit ShaderProgram(const ProgramSource& source);
    GLuint id() const { return program_.id(); }
    void use() const { glUseProgram(program_.id()); }

    // Uniform setters; unknown names (optimized away) are ignored.
    void set(std::string_view name, int value) const;
    void set(std::string_view name, float value) const;
    void set(std::string_view name, const glm::vec2& value) const;
    void set(std::string_view name, const glm::vec3& value) const;
    void set(std::string_view name, const glm::vec4& value) const;
    void set(std::string_view name, const glm::mat3& value) const;
    void set(std::string_view name, const glm::mat4& value) const;
    void set(std::string_view name, const glm::ivec2& value) const;
    void set(std::string_view name, const glm::ivec3& value) const;
    void set(std::string_view name, unsigned value) const;

    // Compute programs: enough work groups of the declared local size for `invocations` threads
    // along x (the shader checks its bound), followed by nothing: callers place the barriers.
    void dispatch_threads(std::size_t invocations, unsigned local_size = 64) const;
    // Compute programs over a 2D grid of threads (an image's pixels, say): enough work groups of
    // the declared local size (x by y) to cover `size`; the shader checks its bounds.
    void dispatch_grid(glm::ivec2 size, glm::uvec2 local_size = {8, 8}) const;

private:
    GLint location(std::string_view name) const;
    ProgramObject program_;
    mutable std::unordered_map<std::string, GLint> locations_;
};

// Programs compiled once per context and shared by every pass and method.
class ShaderCache {
public:
    const ShaderProgram& get(const ProgramSource& source);
    std::size_t size() const { return programs_.size(); }

private:
    std::map<std::string, std::unique_ptr<ShaderProgram>> programs_;
};

}  // namespace bounce::gpu
