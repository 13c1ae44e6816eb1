
#ifndef PYTHONFMU_FMU_EXCEPT_HPP
#define PYTHONFMU_FMU_EXCEPT_HPP

#include <stdexcept>
#include <string>

namespace pythonfmu {

    class fatal_error final : public std::runtime_error {
    public:
        explicit fatal_error(const std::string &msg) : std::runtime_error(msg) {}
    };

    // gear-shaft-bearing patch: a non-OK, non-fatal status (fmi2Warning, fmi2Discard, fmi2Error)
    // reported by the Python slave from a setter or getter; the reason is already in the log.
    class status_error final : public std::runtime_error {
    public:
        explicit status_error(int status) : std::runtime_error("status"), status_(status) {}
        int status() const { return status_; }
    private:
        int status_;
    };


}// namespace pythonfmu

#endif//PYTHONFMU_FMU_EXCEPT_HPP
