// SPDX-License-Identifier: BSD-3-Clause
#include "apcBoundaryExchange.h"

#include "apcBoundaryFaces.h"
#include "apcFrameEngine.h"
#include "apcStageAgreement.h"
#include "apcTestFailures.h"

#include "vtkCommunicator.h"
#include "vtkMPI.h"
#include "vtkMPICommunicator.h"
#include "vtkMultiProcessController.h"

#include <chrono>
#include <climits>
#include <ctime>
#include <exception>
#include <string>
#include <vector>

namespace apc
{
namespace
{
BoundaryExchangeRecord LastExchange;

// Why an exchange stops, agreed by the largest code over the processes.
enum Status : int
{
  Fine = 0,
  Failed = 1,  // an exception on some process
  TooMany = 2, // more faces than an MPI count holds
  NotMPI = 3   // the controller's communicator is not MPI's
};

const char* Explain(int status)
{
  switch (status)
  {
    case TooMany:
      return "more boundary faces than an MPI message counts";
    case NotMPI:
      return "the processes do not talk over MPI";
    default:
      return "a process failed to find or match its faces";
  }
}

double ProcessCPUSeconds()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

MPI_Comm CommunicatorOf(vtkMultiProcessController* controller)
{
  auto* communicator =
    controller ? vtkMPICommunicator::SafeDownCast(controller->GetCommunicator()) : nullptr;
  return communicator && communicator->GetMPIComm() && communicator->GetMPIComm()->GetHandle()
    ? *communicator->GetMPIComm()->GetHandle()
    : MPI_COMM_NULL;
}

// Every process agrees on the worst status (a collective every process joins).
int Agree(const ProcessGroup& group, int status)
{
  int worst = status;
  group.Collective(
    "boundary", [&] { group.Controller->AllReduce(&status, &worst, 1, vtkCommunicator::MAX_OP); });
  return worst;
}

// One volume's exchange; mesh is null on a process that joins with no faces.
int ExchangeVolume(const ProcessGroup& group, CellMesh* mesh)
{
  const int processes = group.Processes;
  const MPI_Comm comm = CommunicatorOf(group.Controller);
  int status = comm == MPI_COMM_NULL ? NotMPI : Fine;
  std::vector<CellMesh::FaceCorners> faces;
  std::vector<int> sendCounts, sendOffsets, receiveCounts, receiveOffsets;
  std::vector<int> sendDoubles, sendDoubleOffsets, receiveDoubles, receiveDoubleOffsets;
  std::vector<CellMesh::FaceCorners> sendFaces;
  std::vector<size_t> sentAs; // face i went out as sendFaces[sentAs[i]]
  std::vector<uint8_t> answers, flags;
  try
  {
    // Every buffer whose size this process knows now (the counts, the answers, the flags) is
    // allocated before the first agreement: one that threw between two later collectives
    // would leave the other processes waiting in the next one.
    for (auto* counts : { &sendCounts, &sendOffsets, &receiveCounts, &receiveOffsets, &sendDoubles,
           &sendDoubleOffsets, &receiveDoubles, &receiveDoubleOffsets })
    {
      counts->assign(static_cast<size_t>(processes), 0);
    }
    ThrowIfFailingForTesting(FailurePoint::BoundaryExchange);
    const auto start = std::chrono::steady_clock::now();
    const double cpu = ProcessCPUSeconds();
    if (mesh)
    {
      // From the piece's own flags (a mesh matched before, for other pieces, starts again).
      mesh->ForgetBoundaryPlanes();
      mesh->FindBoundaryPlanes();
      faces = mesh->GetBoundaryFaces();
    }
    LastExchange.LocalSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    LastExchange.LocalCPUSeconds = ProcessCPUSeconds() - cpu;
    std::vector<int> owners(faces.size());
    for (size_t i = 0; i < faces.size(); ++i)
    {
      owners[i] = FaceOwner(faces[i], processes);
      ++sendCounts[owners[i]];
    }
    for (int p = 1; p < processes; ++p)
    {
      sendOffsets[p] = sendOffsets[p - 1] + sendCounts[p - 1];
    }
    if (faces.size() > static_cast<size_t>(INT_MAX / 12))
    {
      status = std::max(status, static_cast<int>(TooMany));
    }
    sendFaces.resize(faces.size());
    sentAs.resize(faces.size());
    std::vector<int> next = sendOffsets;
    for (size_t i = 0; i < faces.size(); ++i)
    {
      sentAs[i] = static_cast<size_t>(next[owners[i]]++);
      sendFaces[sentAs[i]] = faces[i];
    }
    answers.assign(faces.size(), 0);
    flags.resize(mesh ? faces.size() : 0);
  }
  catch (const std::exception&)
  {
    status = std::max(status, static_cast<int>(Failed));
  }
  status = Agree(group, status);
  if (status != Fine)
  {
    return status;
  }
  LastExchange.FacesSent = static_cast<int64_t>(faces.size());

  // How many faces each owner gets, then the faces (12 doubles each).
  group.Collective("boundary",
    [&] { MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, comm); });
  int64_t received = 0;
  for (int p = 0; p < processes; ++p)
  {
    receiveOffsets[p] = static_cast<int>(received);
    received += receiveCounts[p];
  }
  for (int p = 0; p < processes; ++p)
  {
    sendDoubles[p] = 12 * sendCounts[p];
    sendDoubleOffsets[p] = 12 * sendOffsets[p];
    receiveDoubles[p] = 12 * receiveCounts[p];
    receiveDoubleOffsets[p] = 12 * receiveOffsets[p];
  }
  std::vector<CellMesh::FaceCorners> receivedFaces;
  std::vector<uint8_t> inner;
  status = Fine;
  try
  {
    if (received > INT_MAX / 12)
    {
      status = TooMany;
    }
    receivedFaces.resize(static_cast<size_t>(received));
  }
  catch (const std::exception&)
  {
    status = Failed;
  }
  status = Agree(group, status);
  if (status != Fine)
  {
    return status;
  }
  group.Collective("boundary",
    [&]
    {
      MPI_Alltoallv(sendFaces.data(), sendDoubles.data(), sendDoubleOffsets.data(), MPI_DOUBLE,
        receivedFaces.data(), receiveDoubles.data(), receiveDoubleOffsets.data(), MPI_DOUBLE, comm);
    });
  try
  {
    std::vector<int64_t> counts(receiveCounts.begin(), receiveCounts.end());
    inner = MatchBoundaryFaces(receivedFaces, counts);
  }
  catch (const std::exception&)
  {
    status = Failed;
  }
  status = Agree(group, status);
  if (status != Fine)
  {
    return status;
  }
  // One byte a face back, in the order each process sent them.
  group.Collective("boundary",
    [&]
    {
      MPI_Alltoallv(inner.data(), receiveCounts.data(), receiveOffsets.data(), MPI_UINT8_T,
        answers.data(), sendCounts.data(), sendOffsets.data(), MPI_UINT8_T, comm);
    });
  if (mesh)
  {
    for (size_t i = 0; i < faces.size(); ++i)
    {
      flags[i] = answers[sentAs[i]];
    }
    mesh->ClearBoundaryFaces(flags);
  }
  LastExchange.BytesSent += static_cast<double>(faces.size()) * (sizeof(CellMesh::FaceCorners)) +
    static_cast<double>(received);
  return Fine;
}
}

//------------------------------------------------------------------------------
bool ShareBoundaryFaces(
  const ProcessGroup& group, const CompositeFrame& frame, std::string& problem)
{
  if (!group.Parallel || !frame.ShareBoundary || frame.Volumes < 1)
  {
    return true;
  }
  // The volumes some process needs matched, agreed (a process whose own data did not change
  // joins when another's did: the faces between them may have).
  // Their memory is taken inside the frame's failure agreement, before the first allreduce.
  std::vector<int> need;
  std::vector<int> anyNeeds;
  const std::string failure = AgreeOnFailure(group, "boundary", "the set-up",
    CatchFailure(
      [&]
      {
        ThrowIfFailingForTesting(FailurePoint::BoundarySetUp);
        need.assign(static_cast<size_t>(frame.Volumes), 0);
        for (size_t v = 0; v < frame.Engines.size() && v < need.size(); ++v)
        {
          need[v] = frame.Engines[v]->NeedsSharedBoundary() ? 1 : 0;
        }
        anyNeeds.assign(need.size(), 0);
      }));
  if (!failure.empty())
  {
    // As a failed exchange: nothing was matched, each process weights its own piece's
    // boundary in this frame, and the next frame tries again.
    problem = "Sample End Weights = Boundary: the faces between the processes' pieces were "
              "not matched (" +
      failure +
      "); each process weights its own piece's boundary in this frame, and the next "
      "frame tries again";
    return false;
  }
  group.Collective("boundary",
    [&]
    {
      group.Controller->AllReduce(
        need.data(), anyNeeds.data(), static_cast<vtkIdType>(need.size()), vtkCommunicator::MAX_OP);
    });
  bool fine = true;
  for (size_t v = 0; v < anyNeeds.size(); ++v)
  {
    if (!anyNeeds[v])
    {
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    LastExchange = BoundaryExchangeRecord();
    FrameEngine* engine = v < frame.Engines.size() ? frame.Engines[v] : nullptr;
    CellMesh* mesh =
      engine && engine->RendersBoundaryWeights() ? &engine->GetMeshForSharing() : nullptr;
    const int status = ExchangeVolume(group, mesh);
    LastExchange.Seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (status != Fine)
    {
      // Every process: its own piece's boundary this frame (the engine finds it in Prepare).
      if (mesh)
      {
        mesh->ForgetBoundaryPlanes();
      }
      problem = std::string("Sample End Weights = Boundary: the faces between the processes' "
                            "pieces were not matched (") +
        Explain(status) +
        "); each process weights its own piece's boundary in this frame, and the next frame "
        "tries again";
      fine = false;
    }
  }
  return fine;
}

const BoundaryExchangeRecord& GetLastBoundaryExchange()
{
  return LastExchange;
}

} // namespace apc
