#include "renderer/gpu/shader_program.hpp"

#include "renderer/base/error.hpp"
#include "renderer/gpu/bounds_check.hpp"

#include "common/shared_layout.h"

#include <glm/gtc/type_ptr.hpp>

#include <regex>
#include <set>
#include <sstream>

namespace bounce::gpu {

namespace {

std::string_view find_file(const std::string& path, const std::string& included_from) {
    const auto& files = embedded_shader_files();
    const auto it = files.find(path);
    if (it == files.end()) {
        if (included_from.empty()) BOUNCE_FAIL("shader '{}' is not among the embedded shaders", path);
        BOUNCE_FAIL("shader '{}' includes '{}', which is not among the embedded shaders", included_from, path);
    }
    return it->second;
}

// GLSL wants #extension before any code, so extensions an included file asks for are moved up to
// just after #version (an empty line keeps the file's line numbers).
void expand_into(const std::string& path, const std::string& included_from, ExpandedSource& out,
                 std::set<std::string>& included, bool top_level, const std::vector<std::string>& defines,
                 std::vector<std::string>& extensions) {
    const int file_number = static_cast<int>(out.files.size());
    out.files.push_back(path);
    std::istringstream lines{std::string(find_file(path, included_from))};
    static const std::regex include_pattern(R"(^\s*#\s*include\s+\"([^\"]+)\"\s*$)");
    static const std::regex extension_pattern(R"(^\s*#\s*extension\b.*$)");
    std::string line;
    int line_number = 0;
    bool version_seen = !top_level;
    if (!top_level) out.text += fmt::format("#line 1 {}\n", file_number);
    while (std::getline(lines, line)) {
        ++line_number;
        std::smatch match;
        if (!version_seen && line.rfind("#version", 0) == 0) {
            // Defines go right after #version, which must come first.
            out.text += line + "\n";
            for (const auto& define : defines) out.text += "#define " + define + "\n";
            out.text += fmt::format("#line {} {}\n", line_number + 1, file_number);
            version_seen = true;
        } else if (std::regex_match(line, match, include_pattern)) {
            const std::string include = match[1];
            if (included.insert(include).second) {
                expand_into(include, path, out, included, false, defines, extensions);
            }
            out.text += fmt::format("#line {} {}\n", line_number + 1, file_number);
        } else if (std::regex_match(line, extension_pattern)) {
            if (std::find(extensions.begin(), extensions.end(), line) == extensions.end()) extensions.push_back(line);
            out.text += "\n";
        } else {
            out.text += line + "\n";
        }
    }
    if (!top_level) return;
    if (!version_seen) BOUNCE_FAIL("shader '{}' has no #version line", path);
    std::string hoisted;
    for (const auto& extension : extensions) hoisted += extension + "\n";
    out.text.insert(out.text.find('\n') + 1, hoisted);
}

const char* stage_name(GLenum stage) {
    switch (stage) {
        case GL_VERTEX_SHADER: return "vertex";
        case GL_FRAGMENT_SHADER: return "fragment";
        case GL_GEOMETRY_SHADER: return "geometry";
        case GL_COMPUTE_SHADER: return "compute";
        default: return "shader";
    }
}

ShaderObject compile(GLenum stage, const std::string& path, const std::vector<std::string>& defines) {
    ExpandedSource source = expand_shader_source(path, defines);
    const bool checked = shader_bounds_checks_enabled() ||
                         std::find(defines.begin(), defines.end(), kBoundsCheckDefine) != defines.end();
    if (checked) source = insert_bounds_checks(source, BOUNCE_BINDING_BOUNDS_CHECK);
    ShaderObject shader(glCreateShader(stage));
    const char* text = source.text.c_str();
    glShaderSource(shader.id(), 1, &text, nullptr);
    glCompileShader(shader.id());
    GLint ok = GL_FALSE;
    glGetShaderiv(shader.id(), GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetShaderiv(shader.id(), GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
        glGetShaderInfoLog(shader.id(), length, nullptr, log.data());
        BOUNCE_FAIL("{} shader '{}' failed to compile:\n{}", stage_name(stage), path,
                    annotate_info_log(log, source.files));
    }
    return shader;
}

}  // namespace

std::string ProgramSource::key() const {
    std::string key = vertex + "|" + fragment + "|" + geometry + "|" + compute;
    for (const auto& define : defines) key += "|" + define;
    return key;
}

ExpandedSource expand_shader_source(const std::string& path, const std::vector<std::string>& defines) {
    ExpandedSource out;
    std::set<std::string> included;
    std::vector<std::string> extensions;
    expand_into(path, "", out, included, true, defines, extensions);
    return out;
}

std::string annotate_info_log(const std::string& log, const std::vector<std::string>& files) {
    // Mesa writes "0:12(3): error", NVIDIA "0(12) : error".
    static const std::regex mesa(R"((\d+):(\d+)\((\d+)\))");
    static const std::regex nvidia(R"((\d+)\((\d+)\))");
    auto name = [&](const std::string& number) {
        const std::size_t index = std::stoul(number);
        return index < files.size() ? files[index] : number;
    };
    std::string out;
    std::istringstream lines(log);
    std::string line;
    while (std::getline(lines, line)) {
        std::smatch match;
        if (std::regex_search(line, match, mesa) && match.position(0) == 0) {
            line = fmt::format("{}:{}({}){}", name(match[1]), match[2].str(), match[3].str(), match.suffix().str());
        } else if (std::regex_search(line, match, nvidia) && match.position(0) == 0) {
            line = fmt::format("{}:{}{}", name(match[1]), match[2].str(), match.suffix().str());
        }
        out += line + "\n";
    }
    return out;
}

ShaderProgram::ShaderProgram(const ProgramSource& source) : program_(glCreateProgram()) {
    std::vector<ShaderObject> shaders;
    if (!source.compute.empty()) {
        BOUNCE_CHECK(source.vertex.empty() && source.fragment.empty() && source.geometry.empty(),
                     "compute program '{}' mixed with raster stages", source.compute);
        shaders.push_back(compile(GL_COMPUTE_SHADER, source.compute, source.defines));
    } else {
        shaders.push_back(compile(GL_VERTEX_SHADER, source.vertex, source.defines));
        if (!source.geometry.empty()) shaders.push_back(compile(GL_GEOMETRY_SHADER, source.geometry, source.defines));
        if (!source.fragment.empty()) shaders.push_back(compile(GL_FRAGMENT_SHADER, source.fragment, source.defines));
    }
    for (const auto& shader : shaders) glAttachShader(program_.id(), shader.id());
    glLinkProgram(program_.id());
    for (const auto& shader : shaders) glDetachShader(program_.id(), shader.id());
    GLint ok = GL_FALSE;
    glGetProgramiv(program_.id(), GL_LINK_STATUS, &ok);
    if (!ok) {
        GLint length = 0;
        glGetProgramiv(program_.id(), GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
        glGetProgramInfoLog(program_.id(), length, nullptr, log.data());
        BOUNCE_FAIL("program '{}' failed to link:\n{}", source.key(), log);
    }
}

GLint ShaderProgram::location(std::string_view name) const {
    const std::string key(name);
    const auto it = locations_.find(key);
    if (it != locations_.end()) return it->second;
    const GLint found = glGetUniformLocation(program_.id(), key.c_str());
    locations_.emplace(key, found);
    return found;
}

void ShaderProgram::set(std::string_view name, int value) const { glProgramUniform1i(id(), location(name), value); }
void ShaderProgram::set(std::string_view name, float value) const { glProgramUniform1f(id(), location(name), value); }
void ShaderProgram::set(std::string_view name, const glm::vec2& value) const {
    glProgramUniform2fv(id(), location(name), 1, glm::value_ptr(value));
}
void ShaderProgram::set(std::string_view name, const glm::vec3& value) const {
    glProgramUniform3fv(id(), location(name), 1, glm::value_ptr(value));
}
void ShaderProgram::set(std::string_view name, const glm::vec4& value) const {
    glProgramUniform4fv(id(), location(name), 1, glm::value_ptr(value));
}
void ShaderProgram::set(std::string_view name, const glm::mat3& value) const {
    glProgramUniformMatrix3fv(id(), location(name), 1, GL_FALSE, glm::value_ptr(value));
}
void ShaderProgram::set(std::string_view name, const glm::mat4& value) const {
    glProgramUniformMatrix4fv(id(), location(name), 1, GL_FALSE, glm::value_ptr(value));
}

void ShaderProgram::set(std::string_view name, const glm::ivec2& value) const {
    glProgramUniform2iv(id(), location(name), 1, glm::value_ptr(value));
}

void ShaderProgram::set(std::string_view name, const glm::ivec3& value) const {
    glProgramUniform3iv(id(), location(name), 1, glm::value_ptr(value));
}
void ShaderProgram::set(std::string_view name, unsigned value) const { glProgramUniform1ui(id(), location(name), value); }

void ShaderProgram::dispatch_threads(std::size_t invocations, unsigned local_size) const {
    if (invocations == 0) return;
    use();
    const std::size_t groups = (invocations + local_size - 1) / local_size;
    BOUNCE_CHECK(groups <= 65535u * 65535u, "dispatch of {} threads is too large", invocations);
    // Large dispatches spread over y: a single dimension is limited to 65535 groups.
    const auto x = static_cast<GLuint>(std::min<std::size_t>(groups, 65535));
    const auto y = static_cast<GLuint>((groups + x - 1) / x);
    glDispatchCompute(x, y, 1);
}

void ShaderProgram::dispatch_grid(glm::ivec2 size, glm::uvec2 local_size) const {
    if (size.x <= 0 || size.y <= 0) return;
    use();
    const glm::uvec2 groups = (glm::uvec2(size) + local_size - 1u) / local_size;
    BOUNCE_CHECK(groups.x <= 65535u && groups.y <= 65535u, "dispatch over {}x{} threads is too large", size.x, size.y);
    glDispatchCompute(groups.x, groups.y, 1);
}

const ShaderProgram& ShaderCache::get(const ProgramSource& source) {
    const std::string key = source.key();
    auto it = programs_.find(key);
    if (it == programs_.end()) it = programs_.emplace(key, std::make_unique<ShaderProgram>(source)).first;
    return *it->second;
}

}  // namespace bounce::gpu
