#include "core/net/dds/security_qos.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <string>

namespace keel::net::dds {

namespace {

// Where the builtin security plugins are: Debian ships them in a directory of their own
// beside libddsc (libddsc0debian/), which is not on the loader's path; elsewhere they sit
// beside libddsc. The plugin names then resolve through the loader.
std::string security_plugin(const char* name) {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &info) != 0 &&
        info.dli_fname != nullptr) {
        const std::filesystem::path dir = std::filesystem::path(info.dli_fname).parent_path();
        for (const auto& candidate : {dir / "libddsc0debian", dir}) {
            const std::filesystem::path file = candidate / ("lib" + std::string(name) + ".so");
            std::error_code ignored;
            if (std::filesystem::exists(file, ignored)) return file.string();
        }
    }
    return name;
}

}  // namespace

dds_qos_t* new_security_qos(const SecurityFiles& files) {
    dds_qos_t* qos = dds_create_qos();
    if (qos == nullptr) throw DdsError("dds_create_qos returned nothing");
    auto set = [&](const char* name, const std::string& value) {
        dds_qset_prop(qos, name, value.c_str());
    };
    auto uri = [](const std::string& path) { return "file:" + path; };
    set("dds.sec.auth.library.path", security_plugin("dds_security_auth"));
    set("dds.sec.auth.library.init", "init_authentication");
    set("dds.sec.auth.library.finalize", "finalize_authentication");
    set("dds.sec.crypto.library.path", security_plugin("dds_security_crypto"));
    set("dds.sec.crypto.library.init", "init_crypto");
    set("dds.sec.crypto.library.finalize", "finalize_crypto");
    set("dds.sec.access.library.path", security_plugin("dds_security_ac"));
    set("dds.sec.access.library.init", "init_access_control");
    set("dds.sec.access.library.finalize", "finalize_access_control");
    set("dds.sec.auth.identity_ca", uri(files.identity_ca));
    set("dds.sec.auth.identity_certificate", uri(files.identity_certificate));
    set("dds.sec.auth.private_key", uri(files.private_key));
    set("dds.sec.access.permissions_ca", uri(files.permissions_ca));
    set("dds.sec.access.governance", uri(files.governance));
    set("dds.sec.access.permissions", uri(files.permissions));
    if (!files.crl.empty()) set("org.eclipse.cyclonedds.sec.auth.crl", uri(files.crl));
    return qos;
}

}  // namespace keel::net::dds
