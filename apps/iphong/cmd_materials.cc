#include <cstdio>

#include "iphong/commands.h"
#include "reflectance/material.h"

namespace iphong::cli {

void AddMaterialsCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("materials", "List the named material presets (seeds 000, 004)");
  cmd->callback([] {
    std::printf("%-14s %-20s %-20s %-20s %9s  %s\n", "name", "ka", "kd", "ks", "shininess",
                "source");
    for (const auto& p : reflectance::MaterialPresets()) {
      const auto& m = p.material;
      auto rgb = [](const Vec3d& v) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.2f %.2f %.2f", v[0], v[1], v[2]);
        return std::string(buf);
      };
      std::printf("%-14s %-20s %-20s %-20s %9.1f  %s\n", p.name.c_str(), rgb(m.ka).c_str(),
                  rgb(m.kd).c_str(), rgb(m.ks).c_str(), m.shininess, p.source.c_str());
    }
  });
}

}  // namespace iphong::cli
