#include <vtex/pipelines/run_observer.h>

#include <algorithm>
#include <map>

namespace vtex::pipelines {

std::optional<double> estimateRemainingSeconds(const std::vector<StageTiming>& stages, int jobs) {
    struct Wave {
        double total = 0, longest = 0;
    };
    std::map<std::size_t, Wave> waves;
    for (const StageTiming& s : stages) {
        if (s.state == StageTiming::State::Done) continue;
        double left = 0;
        if (s.state == StageTiming::State::Running && s.fraction > 0 && s.elapsedSeconds > 0)
            left = s.elapsedSeconds * (1 - std::min(1.0, s.fraction)) / std::min(1.0, s.fraction);
        else if (s.expectedSeconds >= 0)
            left = std::max(0.0, s.expectedSeconds - (s.state == StageTiming::State::Running ? s.elapsedSeconds : 0.0));
        else
            return std::nullopt;
        Wave& w = waves[s.wave];
        w.total += left;
        w.longest = std::max(w.longest, left);
    }
    double seconds = 0;
    for (const auto& [index, w] : waves) seconds += std::max(w.longest, w.total / double(std::max(1, jobs)));
    return seconds;
}

}  // namespace vtex::pipelines
